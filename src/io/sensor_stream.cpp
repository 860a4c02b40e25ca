// OpenSensorStream: time offset, time window and the reader thread around
// any SensorBagReader.
#include "rvlio/io/sensor_stream.h"

#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <mutex>
#include <thread>
#include <utility>

namespace rvlio {
namespace {

// Moves scans onto the IMU clock and keeps the messages inside the window.
class WindowedReader final : public SensorBagReader {
 public:
  WindowedReader(std::unique_ptr<SensorBagReader> inner, double time_offset_s,
                 const ReadWindow& window)
      : inner_(std::move(inner)),
        offset_ns_(SecondsToNs(time_offset_s)),
        start_ns_(SecondsToNs(window.start_s)),
        end_ns_(window.duration_s > 0.0 ? start_ns_ + SecondsToNs(window.duration_s) : -1),
        lead_in_ns_(window.start_s > 0.0 ? SecondsToNs(kImuLeadInS) : 0) {}

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    if (ended_) return SensorMessage::kEnd;
    for (;;) {
      StatusOr<SensorMessage> m = inner_->Next(imu, scan);
      if (!m.ok() || *m == SensorMessage::kEnd) return m;
      const bool is_imu = *m == SensorMessage::kImu;
      if (!is_imu && offset_ns_ != 0) ShiftScanTime(offset_ns_, scan);
      const TimeNs t = is_imu ? imu->t_ns : scan->t_end_ns;
      if (!have_first_) first_ns_ = t;
      have_first_ = true;
      const TimeNs rel = t - first_ns_;
      if (end_ns_ >= 0 && rel > end_ns_) {
        ended_ = true;  // the recording is in time order: nothing later is in the window
        return SensorMessage::kEnd;
      }
      if (rel < start_ns_ - (is_imu ? lead_in_ns_ : 0)) continue;
      ++(is_imu ? imu_delivered_ : scans_delivered_);
      return m;
    }
  }

  const SensorReaderStats& stats() const override {
    stats_ = inner_->stats();
    stats_.scans = scans_delivered_;
    stats_.imu_samples = imu_delivered_;
    return stats_;
  }
  std::string lidar_layout() const override { return inner_->lidar_layout(); }
  std::vector<std::string> warnings() const override { return inner_->warnings(); }

 private:
  std::unique_ptr<SensorBagReader> inner_;
  TimeNs offset_ns_, start_ns_, end_ns_, lead_in_ns_;
  TimeNs first_ns_ = 0;
  bool have_first_ = false;
  bool ended_ = false;
  int64_t scans_delivered_ = 0, imu_delivered_ = 0;
  mutable SensorReaderStats stats_;
};

// Runs the wrapped reader on a thread of its own; the consumer sees each
// message with the stats and layout the reader had right after producing it,
// so everything (errors included) arrives exactly as inline reading gives it.
class ThreadedReader final : public SensorBagReader {
 public:
  ThreadedReader(std::unique_ptr<SensorBagReader> inner, const ReaderOptions& io)
      : inner_(std::move(inner)),
        max_messages_(static_cast<size_t>(io.queue_messages)),
        max_bytes_(io.queue_mb * 1e6),
        stats_(inner_->stats()),
        layout_(inner_->lidar_layout()),
        warnings_(inner_->warnings()) {
    thread_ = std::thread([this] { Produce(); });
  }
  ~ThreadedReader() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    not_full_.notify_all();
    thread_.join();
  }
  ThreadedReader(const ThreadedReader&) = delete;
  ThreadedReader& operator=(const ThreadedReader&) = delete;

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    RVLIO_CHECK(imu != nullptr && scan != nullptr);
    if (!error_.ok()) return error_;
    if (ended_) return SensorMessage::kEnd;
    Item item;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      not_empty_.wait(lock, [this] { return !queue_.empty(); });
      item = std::move(queue_.front());
      queue_.pop_front();
      bytes_ -= item.bytes;
    }
    not_full_.notify_one();
    stats_ = item.stats;
    if (item.kind != SensorMessage::kImu) layout_ = std::move(item.layout);
    if (item.kind == SensorMessage::kEnd || !item.error.ok()) warnings_ = std::move(item.warnings);
    if (!item.error.ok()) return error_ = item.error;
    if (item.kind == SensorMessage::kEnd) ended_ = true;
    if (item.kind == SensorMessage::kImu) *imu = item.imu;
    if (item.kind == SensorMessage::kScan) *scan = std::move(item.scan);
    return item.kind;
  }

  const SensorReaderStats& stats() const override { return stats_; }
  std::string lidar_layout() const override { return layout_; }
  std::vector<std::string> warnings() const override { return warnings_; }

 private:
  struct Item {
    SensorMessage kind = SensorMessage::kEnd;
    ImuSample imu;
    Scan scan;
    Status error;
    SensorReaderStats stats;
    std::string layout;  // scans, end and errors only
    std::vector<std::string> warnings;  // end and errors only
    double bytes = 0.0;
  };

  // Reads until the end, the first error or stop_; the last item it queues
  // is the end or the error.
  void Produce() {
    for (;;) {
      Item item;
      StatusOr<SensorMessage> m = inner_->Next(&item.imu, &item.scan);
      if (m.ok()) item.kind = *m;
      else item.error = m.status();
      item.stats = inner_->stats();
      if (item.kind != SensorMessage::kImu || !m.ok()) item.layout = inner_->lidar_layout();
      if (item.kind == SensorMessage::kEnd || !m.ok()) item.warnings = inner_->warnings();
      item.bytes = static_cast<double>(item.scan.points.size() * sizeof(LidarPoint));
      const bool last = !m.ok() || *m == SensorMessage::kEnd;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        not_full_.wait(lock, [this] {
          return stop_ || queue_.empty() ||
                 (queue_.size() < max_messages_ && bytes_ < max_bytes_);
        });
        if (stop_) return;
        bytes_ += item.bytes;
        queue_.push_back(std::move(item));
      }
      not_empty_.notify_one();
      if (last) return;
    }
  }

  std::unique_ptr<SensorBagReader> inner_;  // used by the thread only once it runs
  const size_t max_messages_;
  const double max_bytes_;
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<Item> queue_;
  double bytes_ = 0.0;
  bool stop_ = false;
  std::thread thread_;
  // Consumer side.
  SensorReaderStats stats_;
  std::string layout_;
  std::vector<std::string> warnings_;
  Status error_;
  bool ended_ = false;
};

std::string Seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", s);
  return text;
}

// InvalidInput when the window starts at or after the recording's end.
Status CheckWindow(const std::string& path, const ReadWindow& window) {
  if (!(window.start_s >= 0.0) || !std::isfinite(window.start_s))
    return Status::InvalidInput("--start " + Seconds(window.start_s) + " must be >= 0 s");
  if (!(window.duration_s >= 0.0) || !std::isfinite(window.duration_s))
    return Status::InvalidInput("--duration " + Seconds(window.duration_s) + " must be > 0 s");
  if (window.start_s == 0.0) return Status::Ok();
  StatusOr<BagInfo> info = ReadBagSpan(path);
  if (!info.ok()) return info.status();
  const double length_s = NsToSeconds(info->end_ns - info->start_ns);
  if (window.start_s >= length_s)
    return Status::InvalidInput("recording '" + path + "' is " + Seconds(length_s) +
                                " s long; --start " + Seconds(window.start_s) +
                                " s is at or past its end");
  return Status::Ok();
}

}  // namespace

StatusOr<std::unique_ptr<SensorBagReader>> OpenSensorStream(const std::string& path,
                                                            const LidarOptions& lidar,
                                                            const ImuOptions& imu,
                                                            const ReadWindow& window,
                                                            const ReaderOptions& io) {
  StatusOr<std::unique_ptr<SensorBagReader>> inner = SensorBagReader::Open(path, lidar, imu);
  if (!inner.ok()) return inner.status();
  if (Status s = CheckWindow(path, window); !s.ok()) return s;
  std::unique_ptr<SensorBagReader> reader =
      std::make_unique<WindowedReader>(std::move(inner).value(), lidar.time_offset, window);
  if (io.reader_thread) reader = std::make_unique<ThreadedReader>(std::move(reader), io);
  return reader;
}

}  // namespace rvlio
