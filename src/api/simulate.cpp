// SimulateRecording (rvlio/api.h): runs the deterministic tunnel simulator
// (sim/) and writes
//   DIR/NAME.bag     ROS1 bag: Ouster-layout PointCloud2 + sensor_msgs/Imu
//                    (format mcap: DIR/NAME.mcap, db3: DIR/NAME.db3, ROS 2 CDR;
//                    ouster-pcap: DIR/NAME.pcap + NAME.json, Ouster packets, and
//                    DIR/NAME.bag with the same quantized data; ouster-bag:
//                    DIR/NAME.bag, the packets as the ROS1 driver records
//                    them, + NAME.json)
//   DIR/NAME_gt.tum  true IMU pose in the world frame at 100 Hz
//   DIR/NAME.yaml    sensor configuration for `rvlio run --config`
//   DIR/localizability.csv  with localizability.enabled (default): the true
//                    per-scan localizability (sim/localizability.h,
//                    docs/degeneracy_truth.md)
//   DIR/reference_map.pcd  with survey.enabled: a static survey of the world
//                    (binary PCD, x y z float32, the ground truth's world frame)
// `rvlio simulate` is this call plus argument parsing, signals and its line.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "rvlio/api.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/api/refine_checkpoint.h"
#include "rvlio/formats/ouster.h"
#include "rvlio/formats/pcap.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/formats/crs.h"
#include "rvlio/formats/navsatfix.h"
#include "rvlio/sim/localizability.h"
#include "rvlio/sim/marks.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/simulator.h"

namespace rvlio {
namespace {

constexpr double kGroundTruthRate = 100.0;  // Hz
constexpr const char* kReferenceMapFile = "reference_map.pcd";
constexpr const char* kLocalizabilityFile = "localizability.csv";

// Preset, then seed / duration, then each override (applied last), then
// validation.
Status ResolveOptions(const SimulateArgs& args, SimOptions* options) {
  StatusOr<SimOptions> preset = sim::PresetOptions(args.preset);
  if (!preset.ok()) return preset.status();
  *options = *preset;
  if (args.lidar_msg != "pointcloud2" && args.lidar_msg != "livox")
    return Status::InvalidInput("lidar message type '" + args.lidar_msg +
                                "' is not pointcloud2 or livox");
  if (args.lidar_msg == "livox") {
    options->lidar.topic = "/livox/lidar";
    options->lidar.frame_id = "livox_frame";
  }
  if (args.seed) {
    if (*args.seed < 0)
      return Status::InvalidInput("seed " + std::to_string(*args.seed) + " is negative");
    options->seed = *args.seed;
  }
  if (args.flight_seed) {
    if (*args.flight_seed < 0)
      return Status::InvalidInput("flight seed " + std::to_string(*args.flight_seed) +
                                  " is negative");
    options->flight_seed = *args.flight_seed;
  }
  if (args.reference_map || args.reference_map_only) options->survey.enabled = true;
  if (args.duration_s) {
    if (!(*args.duration_s > 0.0) || !std::isfinite(*args.duration_s))
      return Status::InvalidInput("duration " + std::to_string(*args.duration_s) +
                                  " s is not a positive number of seconds");
    options->duration = *args.duration_s;
  }
  for (const std::string& assignment : args.overrides)
    if (Status s = ApplyOverride(*options, assignment); !s.ok()) return s;
  return options->Validate();
}

// The Ouster ROS driver's topics (its default namespace), for --format ouster-bag.
constexpr const char* kLidarPacketTopic = "/ouster/lidar_packets";
constexpr const char* kImuPacketTopic = "/ouster/imu_packets";
constexpr const char* kMetadataTopic = "/ouster/metadata";

bool OusterFormat(const std::string& format) { return format == "ouster-pcap" || format == "ouster-bag"; }

std::string RecordingExtension(const std::string& format) {
  if (format == "ouster-pcap") return ".pcap";
  return format == "ouster-bag" ? ".bag" : "." + format;
}

// The format and MCAP compression -> writer options and the file extension.
Status ResolveFormat(const SimulateArgs& args, BagWriterOptions* format, std::string* extension) {
  const std::string& name = args.format;
  if (name != "bag" && name != "mcap" && name != "db3" && !OusterFormat(name))
    return Status::InvalidInput("format '" + name +
                                "' is not one of bag, mcap, db3, ouster-pcap, ouster-bag");
  format->format = name == "bag" || OusterFormat(name) ? "ros1" : name;
  *extension = RecordingExtension(name);
  format->mcap_compression = args.mcap_compression;
  const std::string& c = format->mcap_compression;
  if (c != "zstd" && c != "lz4" && c != "none" && c != "unchunked")
    return Status::InvalidInput("MCAP compression '" + c +
                                "' is not one of zstd, lz4, none, unchunked");
  if (c != "zstd" && name != "mcap")
    return Status::InvalidInput("MCAP compression '" + c + "' applies to format mcap only");
  return Status::Ok();
}

// ", flight seed N" when the flight has its own seed ("" otherwise, which
// keeps the files of a default run as they were).
std::string FlightSeedNote(const SimOptions& o) {
  return o.flight_seed >= 0 ? ", flight seed " + std::to_string(o.flight_seed) : "";
}

// The estimator's sensor keys (odometry/options.h) as simulated. The noise
// densities must be positive there; a noise-free simulation gets a tiny value.
// packet_topics: lidar.topic and imu.topic are the Ouster packet topics.
std::string SensorYaml(const SimOptions& o, const std::string& name, bool livox,
                       const std::string& bag_file, bool packet_topics) {
  auto density = [](double v) { return FormatG(std::max(v, 1e-9), 10); };
  const auto& t = o.extrinsics.imu_T_lidar.translation;
  const auto& q = o.extrinsics.imu_T_lidar.rotation_xyzw;
  std::ostringstream y;
  y << "# Sensor configuration of the simulated sequence '" << name << "' (rvlio simulate, seed "
    << o.seed << FlightSeedNote(o) << ").\n# Use: rvlio run --bag " << bag_file << " --config "
    << name << ".yaml --out DIR\n"
    << "lidar:\n"
    << "  topic: " << (packet_topics ? kLidarPacketTopic : o.lidar.topic) << "\n"
    << (livox ? "  type: livox\n" : "  type: ouster\n  header_stamp: start\n")
    << "  min_range: " << FormatG(o.lidar.min_range, 10) << "\n"
    << "  max_range: " << FormatG(o.lidar.max_range, 10) << "\n"
    << "imu:\n"
    << "  topic: " << (packet_topics ? kImuPacketTopic : o.imu.topic) << "\n"
    << "  gyro_noise_density: " << density(o.imu.gyro_noise_density) << "\n"
    << "  accel_noise_density: " << density(o.imu.accel_noise_density) << "\n"
    << "  gyro_bias_random_walk: " << density(o.imu.gyro_bias_random_walk) << "\n"
    << "  accel_bias_random_walk: " << density(o.imu.accel_bias_random_walk) << "\n"
    << "  gravity: " << FormatG(o.imu.gravity, 10) << "\n"
    << "extrinsics:\n"
    << "  imu_T_lidar:\n"
    << "    translation: [" << FormatG(t[0], 10) << ", " << FormatG(t[1], 10) << ", "
    << FormatG(t[2], 10) << "]\n"
    << "    rotation_xyzw: [" << FormatG(q[0], 10) << ", " << FormatG(q[1], 10) << ", "
    << FormatG(q[2], 10) << ", " << FormatG(q[3], 10) << "]\n";
  if (o.marks.enabled)  // the IMU stands world.start_height above a mark (sim/marks.h)
    y << "control:\n  lever_arm: [0, 0, " << FormatG(o.world.start_height, 10) << "]\n";
  if (o.gnss.enabled) {
    const auto& l = o.gnss.lever_arm;
    y << "gnss:\n  topic: " << o.gnss.topic << "\n  lever_arm: [" << FormatG(l[0], 10) << ", "
      << FormatG(l[1], 10) << ", " << FormatG(l[2], 10) << "]\n"
      << "survey:\n  crs: " << o.gnss.crs << "\n";
  }
  // The resolved simulator options, as comments, so the sequence can be
  // reproduced (rvlio simulate --set KEY=VALUE for any of them).
  y << "\n# Simulator options of this sequence:\n";
  std::istringstream dump(DumpYaml(o));
  for (std::string line; std::getline(dump, line);)
    y << (line.empty() ? "#" : "#   " + line) << "\n";
  return y.str();
}

// Streams the simulation into the bag; the first write error stops the run,
// and so does `stop` (*stop_reason set). Either leaves no bag: the writer's
// temporary file (path + ".tmp") is removed when the writer goes.
// fixes: NavSatFix messages (gnss.enabled), each written before the first
// IMU sample that is not older, so the recording stays in time order.
Status WriteBag(const sim::Simulator& simulator, const std::string& path, bool livox,
                const BagWriterOptions& format, const sim::Simulator::TruthCallback& on_truth,
                const std::vector<NavSatFix>& fixes, const StopFn& stop,
                std::string* stop_reason) {
  StatusOr<std::unique_ptr<SensorBagWriter>> writer = SensorBagWriter::Create(path, format);
  if (!writer.ok()) return writer.status();
  const SimOptions& o = simulator.options();
  Status error;
  auto go_on = [&] { return error.ok() && (!stop || (*stop_reason = stop()).empty()); };
  size_t next_fix = 0;
  simulator.Run(
      [&](const ImuSample& m) {
        for (; error.ok() && next_fix < fixes.size() && fixes[next_fix].header_stamp_ns <= m.t_ns;
             ++next_fix)
          error = (*writer)->WriteNavSatFix(o.gnss.topic, fixes[next_fix]);
        if (error.ok()) error = (*writer)->WriteImu(o.imu.topic, o.imu.frame_id, m);
        return go_on();
      },
      [&](const Scan& scan, int rows, int cols) {
        error = livox ? (*writer)->WriteLivoxScan(o.lidar.topic, o.lidar.frame_id, scan)
                      : (*writer)->WriteOusterScan(o.lidar.topic, o.lidar.frame_id, scan, rows, cols);
        return go_on();
      },
      on_truth);
  if (error.ok() && stop_reason->empty()) error = (*writer)->Close();
  writer->reset();  // removes the temporary file unless Close() renamed it
  return error;
}

// The simulated sensor as Ouster metadata (formats/ouster.h), read back from its
// own JSON text so that the writer uses exactly the values a reader parses.
StatusOr<OusterMetadata> SimulatedMetadata(const sim::Simulator& simulator, std::string* json) {
  const sim::LidarModel& lidar = simulator.lidar();
  std::vector<double> altitude_deg;
  for (int r = 0; r < lidar.rows(); ++r)
    altitude_deg.push_back(std::asin(lidar.Direction(r, 0).z()) * 180.0 / M_PI);
  const int rate_hz = static_cast<int>(std::lround(1e9 / static_cast<double>(lidar.period_ns())));
  Eigen::Isometry3d imu_T_lidar = Eigen::Isometry3d::Identity();
  imu_T_lidar.linear() = simulator.T_imu_lidar().R;
  imu_T_lidar.translation() = simulator.T_imu_lidar().t;
  StatusOr<OusterMetadata> meta = SimulatedOusterMetadata(altitude_deg, lidar.cols(), rate_hz, imu_T_lidar);
  if (!meta.ok()) return meta.status();
  *json = OusterMetadataJson(*meta);
  return ParseOusterMetadata(*json, "simulated metadata");
}

// `rvlio simulate --format ouster-pcap`: NAME.pcap (lidar packets on port
// 7502, IMU packets on 7503, IPv4-fragmented at a 1500-byte MTU), NAME.json
// (the metadata) and NAME.bag, the same quantized data as PointCloud2 and
// Imu messages (what the capture must decode to, bit for bit).
// `--format ouster-bag` (packet_bag): the same packets, received at the same
// times, in the ROS1 bag NAME.bag as the ROS driver records them
// (ouster_ros/PacketMsg on /ouster/lidar_packets and /ouster/imu_packets,
// the metadata JSON on /ouster/metadata before them), and NAME.json;
// cloud_bag_path is then unused.
Status WriteOusterCapture(const sim::Simulator& simulator, bool packet_bag,
                          const std::string& recording_path, const std::string& json_path,
                          const std::string& cloud_bag_path,
                          const sim::Simulator::TruthCallback& on_truth, const StopFn& stop,
                          std::string* stop_reason) {
  std::string json;
  StatusOr<OusterMetadata> meta = SimulatedMetadata(simulator, &json);
  if (!meta.ok()) return meta.status();
  PcapWriter pcap;
  if (!packet_bag)
    if (Status s = pcap.Open(recording_path); !s.ok()) return s;
  StatusOr<std::unique_ptr<SensorBagWriter>> bag =
      SensorBagWriter::Create(packet_bag ? recording_path : cloud_bag_path);
  if (!bag.ok()) return bag.status();
  bool metadata_written = false;
  auto write_packet = [&](bool lidar, TimeNs receive_ns, const std::vector<uint8_t>& bytes) {
    const uint16_t port = lidar ? 7502 : 7503;
    if (!packet_bag) return pcap.Write({receive_ns, "", port, port, bytes});
    if (!metadata_written) {  // the driver latches it before the packets
      metadata_written = true;
      if (Status s = (*bag)->WriteString(kMetadataTopic, receive_ns, json); !s.ok()) return s;
    }
    return (*bag)->WriteOusterPacket(lidar ? kLidarPacketTopic : kImuPacketTopic, receive_ns, bytes);
  };
  LidarOptions every_return;
  every_return.min_range = 0.0;
  every_return.max_range = 1e9;
  OusterScanAssembler assembler(*meta, every_return);
  const SimOptions& o = simulator.options();
  Status error;
  uint32_t frame_id = 0;
  auto go_on = [&] { return error.ok() && (!stop || (*stop_reason = stop()).empty()); };
  simulator.Run(
      [&](const ImuSample& m) {
        const OusterImuPacket packet = OusterImuPacketOf(m);
        error = write_packet(false, m.t_ns, EncodeOusterImuPacket(packet));
        if (error.ok() && !packet_bag)
          error = (*bag)->WriteImu(o.imu.topic, o.imu.frame_id, OusterImuToSample(packet));
        return go_on();
      },
      [&](const Scan& scan, int rows, int cols) {
        Scan decoded;
        DecodeStats decode;
        for (const OusterLidarPacket& p : OusterPacketsOfScan(*meta, scan, frame_id)) {
          if (!error.ok()) break;
          error = write_packet(true, p.columns.back().t_ns, EncodeOusterLidarPacket(*meta, p));
          assembler.Add(p, &decoded, &decode);
        }
        ++frame_id;
        if (error.ok() && !packet_bag)
          error = (*bag)->WriteOusterScan(o.lidar.topic, o.lidar.frame_id, decoded, rows, cols);
        return go_on();
      },
      on_truth);
  if (!error.ok() || !stop_reason->empty()) return error;
  if (Status s = (*bag)->Close(); !s.ok()) return s;
  if (Status s = WriteFileAtomically(json_path, json); !s.ok()) return s;
  return packet_bag ? Status::Ok() : pcap.Close();
}

// The fixes of gnss.enabled as NavSatFix messages: survey coordinates to
// latitude, longitude and ellipsoidal height through PROJ (gnss.crs); the
// covariance is the simulated noise's (diagonal known).
StatusOr<std::vector<NavSatFix>> GnssMessages(const sim::Simulator& simulator) {
  const SimGnssOptions& g = simulator.options().gnss;
  std::vector<NavSatFix> out;
  if (!g.enabled) return out;
  StatusOr<GeodeticToCrs> crs = GeodeticToCrs::Create(g.crs);
  if (!crs.ok()) return Status::InvalidInput("gnss.crs: " + crs.status().message());
  for (const sim::SimFix& f : sim::SimulateFixes(simulator)) {
    StatusOr<Eigen::Vector3d> llh = crs->Inverse(f.p_survey);
    if (!llh.ok()) return Status::InvalidInput("gnss.crs '" + g.crs + "': " + llh.status().message());
    NavSatFix m;
    m.header_stamp_ns = f.t_ns;
    m.frame_id = g.frame_id;
    m.status = 2;  // GBAS (RTK)
    m.latitude_deg = (*llh)[0];
    m.longitude_deg = (*llh)[1];
    m.altitude_m = (*llh)[2];
    m.position_covariance = {};
    m.position_covariance[0] = m.position_covariance[4] = std::pow(std::max(g.noise_m, 1e-4), 2);
    m.position_covariance[8] = std::pow(std::max(g.noise_vertical_m, 1e-4), 2);
    m.covariance_type = 2;  // diagonal known
    out.push_back(m);
  }
  return out;
}

// NAME_control.csv (marks.enabled) and NAME_gt_survey.tum (marks or gnss).
Status WriteSurveyFiles(const sim::Simulator& simulator, const std::string& name,
                        OutputStage& stage, SimulateResult* r) {
  const SimOptions& o = simulator.options();
  if (o.marks.enabled) {
    std::string csv = o.marks.times ? "name,x,y,z,role,t_start,t_end\n" : "name,x,y,z,role\n";
    for (const sim::SimMark& m : sim::SimulateMarks(simulator)) {
      csv += m.name + "," + FormatFixed(m.p_survey.x(), 4) + "," + FormatFixed(m.p_survey.y(), 4) +
             "," + FormatFixed(m.p_survey.z(), 4) + "," + (m.check ? "check" : "control");
      if (o.marks.times)
        csv += "," + FormatFixed(NsToSeconds(m.t_start_ns), 3) + "," +
               FormatFixed(NsToSeconds(m.t_end_ns), 3);
      csv += "\n";
    }
    r->control_path = (std::filesystem::path(r->bag_path).parent_path() / (name + "_control.csv")).string();
    if (Status s = WriteFileAtomically(stage.Path(name + "_control.csv"), csv); !s.ok())
      return stage.Explain(s);
  }
  if (!o.marks.enabled && !o.gnss.enabled) return Status::Ok();
  Trajectory gt = simulator.GroundTruth(kGroundTruthRate);
  const Pose3 T_survey_world = sim::SurveyFromWorld(o.marks);
  for (StampedPose& p : gt) {
    const Pose3 T = T_survey_world * Pose3(p.q_world_imu, p.p_world_imu);
    p.p_world_imu = T.t;
    p.q_world_imu = T.quaternion();
  }
  r->gt_survey_path = (std::filesystem::path(r->bag_path).parent_path() / (name + "_gt_survey.tum")).string();
  if (Status s = WriteTum(stage.Path(name + "_gt_survey.tum"), gt,
                          "ground truth of '" + name + "' in the survey frame (marks.survey_frame)");
      !s.ok())
    return stage.Explain(s);
  return Status::Ok();
}

std::string GroundTruthHeader(const SimOptions& o, const std::string& name) {
  return "ground truth of '" + name + "' (rvlio simulate, seed " + std::to_string(o.seed) +
         FlightSeedNote(o) +
         "): T_world_imu, world = gravity-aligned, origin and yaw of the IMU at start";
}

// localizability.csv: one row per scan (sim/localizability.h). Eigenvalues
// of the translation information per point (sum 1), the weak direction
// (world, unit), lambda_min / lambda_max, the pose information's smallest
// eigenvalue and eigenvector (rotation rad first, then translation m).
Status WriteLocalizabilityCsv(const std::string& path,
                              const std::vector<sim::ScanLocalizability>& scans) {
  std::ostringstream os;
  os.precision(9);
  os << "t,points,lambda_min,lambda_mid,lambda_max,weak_dir_x,weak_dir_y,weak_dir_z,ratio,"
        "pose_lambda_min,pose_weak_rx,pose_weak_ry,pose_weak_rz,pose_weak_tx,pose_weak_ty,"
        "pose_weak_tz,degenerate\n";
  for (const sim::ScanLocalizability& l : scans) {
    os << FormatSeconds(l.t_ns) << ',' << l.points;
    for (int i = 0; i < 3; ++i) os << ',' << l.eigenvalues[i];
    for (int i = 0; i < 3; ++i) os << ',' << l.weak_dir_world[i];
    os << ',' << l.ratio << ',' << l.pose_eigenvalue_min;
    for (int i = 0; i < 6; ++i) os << ',' << l.pose_weak[i];
    os << ',' << (l.degenerate ? 1 : 0) << '\n';
  }
  return WriteFileAtomically(path, os.str());
}

// The reference map (options.survey), surveyed before anything is written
// so that a bad crop leaves no file.
Status RunSurvey(const sim::Simulator& simulator, SimulateResult* r,
                 std::vector<Eigen::Vector3d>* p_world) {
  const auto wall0 = std::chrono::steady_clock::now();
  StatusOr<sim::SurveyResult> survey = simulator.Survey();
  if (!survey.ok()) return survey.status();
  r->reference_map_points = static_cast<int64_t>(survey->p_world.size());
  r->reference_map_stations = static_cast<int>(survey->stations.size());
  r->reference_map_s = SecondsSince(wall0);
  *p_world = std::move(survey->p_world);
  return Status::Ok();
}

// simulation.json: what this folder simulated (rvlio/api.h
// kSimulationFile), so that `eval --degeneracy` can tell whether a run read
// this folder's recording. `recording_file` is the staged recording, hashed
// as written (FileContentHash).
StatusOr<nlohmann::json> SimulationIdentity(const SimulateArgs& args, const SimOptions& o,
                                            const std::string& name, const std::string& recording,
                                            const std::string& recording_file,
                                            const std::vector<sim::ScanLocalizability>& truth,
                                            const SimulateResult& r) {
  StatusOr<uint64_t> hash = FileContentHash(recording_file);
  if (!hash.ok()) return hash.status();
  nlohmann::json j = {{"command", "simulate"},
                      {"version", RVLIO_VERSION},
                      {"preset", args.preset},
                      {"name", name},
                      {"seed", o.seed},
                      {"flight_seed", o.flight_seed},
                      {"duration_s", o.duration},
                      {"start_time_s", o.start_time},
                      {"recording", recording},
                      {"recording_hash", HashText(*hash)},
                      {"scans", r.scans},
                      {"localizability_scans", truth.size()}};
  if (!truth.empty())
    j["localizability_stamps_s"] = {{"first", NsToSeconds(truth.front().t_ns)},
                                    {"last", NsToSeconds(truth.back().t_ns)}};
  return j;
}

}  // namespace

std::string SimulatedRecordingPath(const SimulateArgs& args) {
  const std::string name = args.name.empty() ? args.preset : args.name;
  return (std::filesystem::path(args.out_dir) / (name + RecordingExtension(args.format))).string();
}

StatusOr<SimulateResult> SimulateRecording(const SimulateArgs& args) {
  SimOptions options;
  if (Status s = ResolveOptions(args, &options); !s.ok()) return s;
  const std::string name = args.name.empty() ? args.preset : args.name;
  if (name.empty() || name.find('/') != std::string::npos)
    return Status::InvalidInput("name '" + name + "' must be a plain file stem");
  if (args.out_dir.empty()) return Status::IoError("cannot create output directory ''");
  const std::filesystem::path dir = args.out_dir;
  OutputFolder out_folder(args.out_dir);  // removed again when nothing gets written
  if (Status s = out_folder.Prepare(); !s.ok()) return s;
  BagWriterOptions format;
  std::string extension;
  if (Status s = ResolveFormat(args, &format, &extension); !s.ok()) return s;
  // The sensor configuration must be one that `rvlio run` accepts.
  const bool livox = args.lidar_msg == "livox";
  const std::string yaml =
      SensorYaml(options, name, livox, name + extension, args.format == "ouster-bag");
  Configuration check;
  if (Status s = ApplyYamlText(check, yaml, name + ".yaml");
      !s.ok() || !(s = check.Validate()).ok())
    return Status::Internal("generated sensor configuration is rejected: " + s.message());

  const auto wall0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  StatusOr<std::unique_ptr<sim::Simulator>> simulator = sim::Simulator::Create(options);
  if (!simulator.ok()) return simulator.status();
  SimulateResult r;
  std::vector<Eigen::Vector3d> reference_map;
  if (options.survey.enabled) {
    if (Status s = RunSurvey(**simulator, &r, &reference_map); !s.ok()) return s;
  }
  // Every file is written into a staging folder and moved into place when all
  // are complete: a failure (disk full, file-size limit, a stop) leaves the
  // folder as it was, and a folder this call created is removed again.
  OutputStage stage(args.out_dir);
  if (Status s = stage.Open(); !s.ok()) return s;
  const std::string map_path = (dir / kReferenceMapFile).string();
  if (args.reference_map_only) {
    if (Status s = WriteMapPcd(stage.Path(kReferenceMapFile), reference_map); !s.ok())
      return stage.Explain(s);
    if (Status s = stage.Commit(); !s.ok()) return s;
    out_folder.Keep();
    r.reference_map_path = map_path;
    r.wall_s = SecondsSince(wall0);
    r.cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
    return r;
  }
  const std::string recording = name + extension;
  r.bag_path = (dir / recording).string();
  const std::string staged_recording = stage.Path(recording);
  if (args.staged) args.staged(staged_recording);
  StatusOr<std::vector<NavSatFix>> fixes = GnssMessages(**simulator);
  if (!fixes.ok()) return fixes.status();
  if (!fixes->empty() && OusterFormat(args.format))
    return Status::InvalidInput("gnss.enabled: format " + args.format +
                                " holds no NavSatFix messages");
  sim::LocalizabilityTruth truth(options.localizability, options.lidar);
  std::vector<sim::ScanLocalizability> localizability;
  sim::Simulator::TruthCallback on_truth;
  if (options.localizability.enabled)
    on_truth = [&](const Scan& scan, std::vector<sim::SurfaceHit>* hits) {
      localizability.push_back(truth.Compute((*simulator)->world(), scan, hits));
    };
  const Status written =
      OusterFormat(args.format)
          ? WriteOusterCapture(**simulator, args.format == "ouster-bag", staged_recording,
                               stage.Path(name + ".json"),
                               args.format == "ouster-pcap" ? stage.Path(name + ".bag") : "",
                               on_truth, args.stop, &r.stop_reason)
          : WriteBag(**simulator, staged_recording, livox, format, on_truth, *fixes, args.stop,
                     &r.stop_reason);
  if (!written.ok()) return stage.Explain(written);
  if ((r.stopped = !r.stop_reason.empty())) return r;
  r.wall_s = SecondsSince(wall0);
  r.cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;

  r.gt_path = (dir / (name + "_gt.tum")).string();
  const Trajectory gt = (*simulator)->GroundTruth(kGroundTruthRate);
  if (Status s = WriteTum(stage.Path(name + "_gt.tum"), gt, GroundTruthHeader(options, name));
      !s.ok())
    return stage.Explain(s);
  if (Status s = WriteSurveyFiles(**simulator, name, stage, &r); !s.ok()) return s;
  r.config_path = (dir / (name + ".yaml")).string();
  if (Status s = WriteFileAtomically(stage.Path(name + ".yaml"), yaml); !s.ok())
    return stage.Explain(s);
  if (options.localizability.enabled) {
    r.localizability_path = (dir / kLocalizabilityFile).string();
    if (Status s = WriteLocalizabilityCsv(stage.Path(kLocalizabilityFile), localizability);
        !s.ok())
      return stage.Explain(s);
    r.degenerate_scans = std::count_if(localizability.begin(), localizability.end(),
                                       [](const sim::ScanLocalizability& l) { return l.degenerate; });
  }
  if (options.survey.enabled) {
    if (Status s = WriteMapPcd(stage.Path(kReferenceMapFile), reference_map); !s.ok())
      return stage.Explain(s);
    r.reference_map_path = map_path;
  }
  r.scans = (*simulator)->scan_count();
  r.imu_samples = (*simulator)->imu_count();
  r.rows = (*simulator)->lidar().rows();
  r.cols = (*simulator)->lidar().cols();
  r.duration_s = options.duration;
  StatusOr<nlohmann::json> identity =
      SimulationIdentity(args, options, name, recording, staged_recording, localizability, r);
  if (!identity.ok()) return stage.Explain(identity.status());
  if (Status s = WriteFileAtomically(stage.Path(kSimulationFile), JsonText(*identity) + "\n");
      !s.ok())
    return stage.Explain(s);
  if (Status s = stage.Commit(); !s.ok()) return s;
  out_folder.Keep();
  return r;
}

}  // namespace rvlio
