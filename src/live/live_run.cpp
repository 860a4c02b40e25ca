// RunLive (rvlio/live/live.h): a transport feeding a LiveSensorSource that
// RunRecording reads, and a LivePublisher fed by both.
#include <algorithm>
#include <atomic>
#include <chrono>

#include "publisher.h"
#include "rvlio/api/result_json.h"
#include "rvlio/formats/ouster.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/live/live.h"
#include "transport.h"

namespace rvlio {
namespace {

using live_detail::Transport;

constexpr int kLidarDepth = 4;    // scans a transport holds for the LiDAR thread
constexpr int kImuDepth = 1000;   // messages for the IMU thread (2.5 s at 400 Hz)

// Messages of kLidarDepth scans: Ouster packets come many to a scan.
int LidarDepth(const std::optional<OusterMetadata>& ouster) {
  if (!ouster) return kLidarDepth;
  const int per_packet = std::max(ouster->columns_per_packet, 1);
  return kLidarDepth * ((ouster->WindowColumns() + per_packet - 1) / per_packet);
}

// The sensor of Ouster packet topics (lidar.ouster_metadata, when given),
// read before connecting; it gives the default extrinsic as it does to
// `run` on a packet recording (*notes says so).
Status LoadOusterSensor(Configuration* options, std::optional<OusterMetadata>* ouster,
                        std::vector<std::string>* notes) {
  const std::string& path = options->lidar.ouster_metadata;
  if (path.empty()) return Status::Ok();
  StatusOr<OusterMetadata> meta = ReadOusterMetadataFile(path);
  if (!meta.ok()) return meta.status();
  *ouster = std::move(meta).value();
  ApplyOusterExtrinsics(**ouster, path, &options->extrinsics, notes);
  return Status::Ok();
}

nlohmann::json LiveJson(const LiveFigures& f) {
  return {{"middleware", f.middleware},
          {"origin", f.origin},
          {"lidar_messages", f.lidar_messages},
          {"imu_messages", f.imu_messages},
          {"scans_dropped", f.scans_dropped},
          {"imu_dropped", f.imu_dropped},
          {"imu_odometry", f.imu_odometry},
          {"imu_input_hz", f.imu_input_hz},
          {"imu_odometry_hz", f.imu_odometry_hz},
          {"latency_ms",
           {{"samples", f.latency_samples},
            {"median", f.latency_median_ms},
            {"p95", f.latency_p95_ms},
            {"max", f.latency_max_ms},
            {"imu_wait_median", f.imu_wait_median_ms},
            {"after_imu_median", f.after_imu_median_ms},
            {"after_imu_p95", f.after_imu_p95_ms}}}};
}

StatusOr<std::unique_ptr<Transport>> Connect(const LiveArgs& args,
                                             const std::function<bool()>& stopped) {
  if (args.middleware == LiveMiddleware::kRos1)
    return live_detail::ConnectRos1(args.options.live, args.node_name, stopped);
  return live_detail::ConnectRos2(args.options.live);
}

}  // namespace

StatusOr<LiveResult> RunLive(const LiveArgs& args) {
  Configuration options = args.options;
  if (Status s = options.Validate(); !s.ok()) return s;
  std::optional<OusterMetadata> ouster;
  std::vector<std::string> notes;
  if (Status s = LoadOusterSensor(&options, &ouster, &notes); !s.ok()) return s;
  if (!args.out_dir.empty()) {  // an unusable output folder is refused before connecting
    OutputFolder check(args.out_dir);  // removes again what it created
    if (Status s = check.Prepare(); !s.ok()) return s;
  }
  // The stop request, read while connecting and by the source while it waits.
  std::string stop_reason;
  auto stop = [&args, &stop_reason]() -> std::string {
    if (stop_reason.empty() && args.stop) stop_reason = args.stop();
    return stop_reason;
  };
  StatusOr<std::unique_ptr<Transport>> transport = Connect(args, [&stop] { return !stop().empty(); });
  if (!transport.ok()) return transport.status();
  if (*transport == nullptr) {  // stopped while waiting for the master
    LiveResult out;
    out.run.stopped = true;
    out.run.stop_reason = stop_reason;
    return out;
  }
  Transport& net = **transport;

  LiveSourceOptions source_options;
  source_options.encoding = net.encoding();
  source_options.origin = net.origin();
  source_options.lidar = options.lidar;
  source_options.imu = options.imu;
  source_options.live = options.live;
  source_options.ouster = ouster;
  source_options.ouster_origin = options.lidar.ouster_metadata;
  source_options.stopped = [&stop] { return !stop().empty(); };
  LiveSensorSource source(source_options);
  live_detail::LivePublisher publisher(&net, &source, options);
  // The transport's threads call into source and publisher: they stop
  // before those go, on every way out of this function.
  struct StopReceiving {
    Transport* net;
    ~StopReceiving() { net->Shutdown(); }
  } stop_receiving{&net};

  if (Status s = net.Advertise(live_detail::OutputTopics(options.live.topic_namespace)); !s.ok())
    return s;
  Status subscribed = net.Subscribe(
      options.lidar.topic, LidarDepth(ouster),
      [&source](const uint8_t* data, size_t size, const std::string& type) {
        source.PushLidar(data, size, type, std::chrono::steady_clock::now());
      });
  if (subscribed.ok())
    subscribed = net.Subscribe(options.imu.topic, kImuDepth,
                               [&source, &publisher](const uint8_t* data, size_t size,
                                                     const std::string& type) {
                                 for (const ImuSample& s : source.PushImu(data, size, type))
                                   publisher.OnImu(s);
                               });
  if (!subscribed.ok()) return subscribed;
  if (args.on_ready) args.on_ready(net.origin());

  RunArgs run;
  run.bag = net.origin();
  run.options = options;
  run.out_dir = args.out_dir;
  run.map = args.map;
  run.initial_pose = args.initial_pose;
  run.initial_pose_tum = args.initial_pose_tum;
  run.source = &source;
  // No run.stop: a stop ends the live input (the source delivers what it
  // received, then its end), and the run finishes as at the end of a
  // recording, so the outputs hold every scan received, as `run` on a
  // recording of the same messages.
  run.progress = args.progress;
  run.on_result = [&publisher](const ScanResult& r, const Odometry& odo, const LocalOrigin& origin) {
    publisher.OnResult(r, odo, origin);
  };
  LiveFigures figures;
  figures.middleware = args.middleware == LiveMiddleware::kRos1 ? "ros1" : "ros2";
  figures.origin = net.origin();
  auto fill = [&] {
    const LiveSourceStats s = source.live_stats();
    figures.lidar_messages = s.lidar_messages;
    figures.imu_messages = s.imu_messages;
    figures.scans_dropped = s.scans_dropped;
    figures.imu_dropped = s.imu_dropped;
    publisher.Fill(&figures);
  };
  const SummaryAnnotator annotate = [&](nlohmann::json* summary) {
    net.Shutdown();  // nothing arrives any more: the figures are final
    fill();
    (*summary)["command"] = "live";
    if (!notes.empty()) {  // as run's summary says them, first
      nlohmann::json warnings = notes;
      for (const nlohmann::json& w : (*summary)["warnings"]) warnings.push_back(w);
      (*summary)["warnings"] = warnings;
    }
    (*summary)["live"] = LiveJson(figures);
    (*summary)["interrupted"] = !stop_reason.empty();
    if (!stop_reason.empty()) {  // as an interrupted `run` says it
      (*summary)["signal"] = stop_reason;
      (*summary)["last_stamp_s"] = NsToSeconds(std::max<TimeNs>(publisher.last_result_ns(), 0));
    }
  };
  StatusOr<RunResult> result = RunRecordingAnnotated(run, annotate);
  net.Shutdown();
  if (result.ok()) net.Flush();  // the poses of the last scans reach the subscribers
  fill();
  LiveResult out;
  out.figures = figures;
  if (!result.ok()) {
    // Stopped before a scan was done: nothing written, as `run` stopped then.
    if (stop_reason.empty() || !source.error().ok()) return result.status();
    out.run.stopped = true;
    out.run.stop_reason = stop_reason;
    return out;
  }
  out.run = std::move(result).value();
  out.run.warnings.insert(out.run.warnings.begin(), notes.begin(), notes.end());
  out.run.stopped = !stop_reason.empty();
  out.run.stop_reason = stop_reason;
  return out;
}

}  // namespace rvlio
