// OpenSensorStream: time offset, time window and the reader thread around
// any SensorBagReader.
#include "rvlio/formats/sensor_stream.h"

#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "rvlio/common/text.h"

namespace rvlio {
namespace {

// A message read ahead and held to be delivered in order.
struct HeldMessage {
  SensorMessage kind = SensorMessage::kEnd;  // kImu or kScan
  ImuSample imu;
  Scan scan;
};

// Delivers the oldest held message (there is one).
SensorMessage PopHeld(std::deque<HeldMessage>* held, ImuSample* imu, Scan* scan) {
  HeldMessage& h = held->front();
  const SensorMessage kind = h.kind;
  if (kind == SensorMessage::kImu) *imu = h.imu;
  else *scan = std::move(h.scan);
  held->pop_front();
  return kind;
}

// Moves scans onto the IMU clock and keeps the messages inside the window.
class WindowedReader final : public SensorBagReader {
 public:
  // `first_ns`: the recording's first delivered stamp when known (the inner
  // reader may then start later in the recording), else the first it delivers.
  WindowedReader(std::unique_ptr<SensorBagReader> inner, double time_offset_s,
                 const ReadWindow& window, std::optional<TimeNs> first_ns)
      : inner_(std::move(inner)),
        offset_ns_(SecondsToNs(time_offset_s)),
        start_ns_(SecondsToNs(window.start_s)),
        end_ns_(window.duration_s > 0.0 ? start_ns_ + SecondsToNs(window.duration_s) : -1),
        lead_in_ns_(window.start_s > 0.0 ? SecondsToNs(kImuLeadInS) : 0),
        first_ns_(first_ns.value_or(0)),
        have_first_(first_ns.has_value()) {}

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    if (ended_) return SensorMessage::kEnd;
    for (;;) {
      const bool read_ahead = !ahead_.empty();
      StatusOr<SensorMessage> m =
          read_ahead ? StatusOr<SensorMessage>(PopHeld(&ahead_, imu, scan)) : ReadShifted(imu, scan);
      if (!m.ok() || *m == SensorMessage::kEnd) return m;
      const bool is_imu = *m == SensorMessage::kImu;
      const TimeNs rel = Relative(is_imu ? imu->t_ns : scan->t_end_ns);
      if (end_ns_ >= 0 && rel > end_ns_) {
        // The recording is in time order: nothing later is in the window,
        // unless this is a scan whose stamp jumped ahead (a bit flip in a
        // header stamp, lidar/scan_order.h): then the next scan is inside
        // the window, and only this one is left out.
        if (!is_imu && !read_ahead && NextScanInWindow()) continue;
        ended_ = true;
        return SensorMessage::kEnd;
      }
      // Only a --start selects: without one, scans that lidar.time_offset moved
      // before the recording's first stamp are delivered (and counted where
      // they are dropped), not skipped here unseen.
      if (start_ns_ > 0 && rel < start_ns_ - (is_imu ? lead_in_ns_ : 0)) continue;
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
  bool truncated() const override { return inner_->truncated(); }

 private:
  // The inner reader's next message, its scan moved onto the IMU clock.
  StatusOr<SensorMessage> ReadShifted(ImuSample* imu, Scan* scan) {
    StatusOr<SensorMessage> m = inner_->Next(imu, scan);
    if (m.ok() && *m == SensorMessage::kScan && offset_ns_ != 0) ShiftScanTime(offset_ns_, scan);
    return m;
  }
  // The stamp relative to the recording's first delivered stamp.
  TimeNs Relative(TimeNs t_ns) {
    if (!have_first_) first_ns_ = t_ns;
    have_first_ = true;
    return t_ns - first_ns_;
  }
  // Reads up to the next scan (kept in ahead_ with the IMU samples before
  // it): whether it ends inside the window. At the end of input or an error
  // the window ends where it was, as without the look.
  bool NextScanInWindow() {
    for (;;) {
      HeldMessage m;
      StatusOr<SensorMessage> kind = ReadShifted(&m.imu, &m.scan);
      if (!kind.ok() || *kind == SensorMessage::kEnd) return false;
      m.kind = *kind;
      const TimeNs t_ns = m.kind == SensorMessage::kImu ? m.imu.t_ns : m.scan.t_end_ns;
      ahead_.push_back(std::move(m));
      if (ahead_.back().kind == SensorMessage::kScan) return t_ns - first_ns_ <= end_ns_;
    }
  }

  std::unique_ptr<SensorBagReader> inner_;
  TimeNs offset_ns_, start_ns_, end_ns_, lead_in_ns_;
  TimeNs first_ns_;
  bool have_first_;
  bool ended_ = false;
  std::deque<HeldMessage> ahead_;  // read past a scan stamped past the window's end
  int64_t scans_delivered_ = 0, imu_delivered_ = 0;
  mutable SensorReaderStats stats_;
};

// Receive time (before the window's first needed stamp) from which a
// windowed read starts: messages received earlier are neither read nor
// decoded. Header stamps may trail or lead receive times; the check below
// keeps the read exact whatever the margin.
constexpr TimeNs kSkipMarginNs = 2000000000;  // 2 s
// Decoded scan memory a SkipAheadReader holds while it checks its start, at
// most (past it, the recording is read from its start).
constexpr size_t kSkipCheckBytes = size_t{256} << 20;

// The window's first needed stamps, on the IMU clock: IMU samples from
// `imu_ns`, scans ending from `scan_ns` (earlier ones WindowedReader drops).
struct SkipThresholds {
  TimeNs imu_ns = 0, scan_ns = 0;
};

// Reads a recording from a receive time on (SensorBagReader::Open with a
// ReceiveTimeRange) and checks that nothing the window needs was received
// before it: the first IMU sample read must be older than thresholds.imu_ns
// and the first scan end (after the time offset) older than
// thresholds.scan_ns; as each topic's stamps rise in receive order (which
// WindowedReader assumes too), every skipped message is then older still.
// Otherwise (or when a topic has no message in the range) it reads the
// recording from its start instead, so the window gets exactly the messages
// a full read gives it. Messages are held until both checks are done.
class SkipAheadReader final : public SensorBagReader {
 public:
  SkipAheadReader(std::string path, LidarOptions lidar, ImuOptions imu,
                  const SkipThresholds& thresholds)
      : path_(std::move(path)),
        lidar_(std::move(lidar)),
        imu_(std::move(imu)),
        offset_ns_(SecondsToNs(lidar_.time_offset)),
        thresholds_(thresholds) {}

  // Opens the range from `first_receive_ns`; reads ahead until both checks
  // are done.
  Status Init(TimeNs first_receive_ns) {
    StatusOr<std::unique_ptr<SensorBagReader>> ranged = SensorBagReader::Open(
        path_, lidar_, imu_, ReceiveTimeRange{first_receive_ns, std::numeric_limits<TimeNs>::max()});
    if (!ranged.ok()) return ranged.status();
    inner_ = std::move(ranged).value();
    bool imu_checked = false, scan_checked = false;
    size_t held_bytes = 0;
    while (!(imu_checked && scan_checked)) {
      HeldMessage held;
      StatusOr<SensorMessage> kind = inner_->Next(&held.imu, &held.scan);
      if (!kind.ok() || *kind == SensorMessage::kEnd || held_bytes > kSkipCheckBytes)
        return ReadFromStart();  // a read from the start meets the same error in its place
      held.kind = *kind;
      held_bytes += sizeof(HeldMessage) + held.scan.points.size() * sizeof(LidarPoint);
      const bool is_imu = *kind == SensorMessage::kImu;
      bool& checked = is_imu ? imu_checked : scan_checked;
      if (!checked) {
        const TimeNs t = is_imu ? held.imu.t_ns : held.scan.t_end_ns + offset_ns_;
        if (t >= (is_imu ? thresholds_.imu_ns : thresholds_.scan_ns)) return ReadFromStart();
        checked = true;
      }
      held_.push_back(std::move(held));
    }
    return Status::Ok();
  }

  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override {
    if (held_.empty()) return inner_->Next(imu, scan);
    return PopHeld(&held_, imu, scan);
  }

  const SensorReaderStats& stats() const override { return inner_->stats(); }
  std::string lidar_layout() const override { return inner_->lidar_layout(); }
  std::vector<std::string> warnings() const override { return inner_->warnings(); }
  bool truncated() const override { return inner_->truncated(); }

 private:
  Status ReadFromStart() {
    held_.clear();
    StatusOr<std::unique_ptr<SensorBagReader>> full = SensorBagReader::Open(path_, lidar_, imu_);
    if (!full.ok()) return full.status();
    inner_ = std::move(full).value();
    return Status::Ok();
  }

  std::string path_;
  LidarOptions lidar_;
  ImuOptions imu_;
  TimeNs offset_ns_;
  SkipThresholds thresholds_;
  std::unique_ptr<SensorBagReader> inner_;
  std::deque<HeldMessage> held_;  // read while checking the start, not yet returned
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
        warnings_(inner_->warnings()),
        truncated_(inner_->truncated()) {
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
    if (item.kind == SensorMessage::kEnd || !item.error.ok()) {
      warnings_ = std::move(item.warnings);
      truncated_ = item.truncated;
    }
    if (!item.error.ok()) return error_ = item.error;
    if (item.kind == SensorMessage::kEnd) ended_ = true;
    if (item.kind == SensorMessage::kImu) *imu = item.imu;
    if (item.kind == SensorMessage::kScan) *scan = std::move(item.scan);
    return item.kind;
  }

  const SensorReaderStats& stats() const override { return stats_; }
  std::string lidar_layout() const override { return layout_; }
  std::vector<std::string> warnings() const override { return warnings_; }
  bool truncated() const override { return truncated_; }

 private:
  struct Item {
    SensorMessage kind = SensorMessage::kEnd;
    ImuSample imu;
    Scan scan;
    Status error;
    SensorReaderStats stats;
    std::string layout;  // scans, end and errors only
    std::vector<std::string> warnings;  // end and errors only
    bool truncated = false;             // end and errors only
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
      if (item.kind == SensorMessage::kEnd || !m.ok()) {
        item.warnings = inner_->warnings();
        item.truncated = inner_->truncated();
      }
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
  bool truncated_ = false;
  Status error_;
  bool ended_ = false;
};

}  // namespace

WindowSpan SpanOfWindow(double start_s, double end_s, const ReadWindow& window) {
  WindowSpan span;
  span.first_s = std::min(end_s, start_s + window.start_s);
  span.last_s = window.duration_s > 0.0 ? std::min(end_s, span.first_s + window.duration_s) : end_s;
  return span;
}

namespace {

// InvalidInput when the window starts at or after the recording's end.
// *first_receive_ns: the recording's first receive time (start > 0 only).
Status CheckWindow(const std::string& path, const ReadWindow& window, TimeNs* first_receive_ns) {
  if (!(window.start_s >= 0.0) || !std::isfinite(window.start_s))
    return Status::InvalidInput("--start " + FormatFixed(window.start_s, 3) + " must be >= 0 s");
  if (!(window.duration_s >= 0.0) || !std::isfinite(window.duration_s))
    return Status::InvalidInput("--duration " + FormatFixed(window.duration_s, 3) +
                                " must be > 0 s");
  if (window.start_s == 0.0) return Status::Ok();
  StatusOr<BagInfo> info = ReadBagSpan(path);
  if (!info.ok()) return info.status();
  *first_receive_ns = info->start_ns;
  const double length_s = NsToSeconds(info->end_ns - info->start_ns);
  if (window.start_s >= length_s)
    return Status::InvalidInput("recording '" + path + "' is " + FormatFixed(length_s, 3) +
                                " s long; --start " + FormatFixed(window.start_s, 3) +
                                " s is at or past its end");
  return Status::Ok();
}

// A window starting at window.start_s > 0: the recording's first stamp
// (*first_ns, from the first message of `full`, a reader at the recording's
// start, which it then no longer uses) and a SkipAheadReader from a receive
// time kSkipMarginNs before the window's first needed stamp (counted from the
// recording's first receive time). Null (read `full` from its start, as
// without a window) when that receive time is not after the first.
StatusOr<std::unique_ptr<SensorBagReader>> SkipAhead(const std::string& path,
                                                     const LidarOptions& lidar,
                                                     const ImuOptions& imu,
                                                     const ReadWindow& window,
                                                     TimeNs first_receive_ns,
                                                     SensorBagReader* full,
                                                     std::optional<TimeNs>* first_ns) {
  const TimeNs skip_ns = SecondsToNs(window.start_s) - SecondsToNs(kImuLeadInS) - kSkipMarginNs;
  if (skip_ns <= 0) return std::unique_ptr<SensorBagReader>();
  ImuSample first_imu;
  Scan first_scan;
  StatusOr<SensorMessage> first = full->Next(&first_imu, &first_scan);
  if (!first.ok()) return first.status();
  if (*first == SensorMessage::kEnd) return std::unique_ptr<SensorBagReader>();  // no sensor message
  *first_ns = *first == SensorMessage::kImu
                  ? first_imu.t_ns
                  : first_scan.t_end_ns + SecondsToNs(lidar.time_offset);
  const TimeNs start_ns = **first_ns + SecondsToNs(window.start_s);
  const SkipThresholds thresholds{start_ns - SecondsToNs(kImuLeadInS), start_ns};
  auto reader = std::make_unique<SkipAheadReader>(path, lidar, imu, thresholds);
  if (Status s = reader->Init(first_receive_ns + skip_ns); !s.ok()) return s;
  return std::unique_ptr<SensorBagReader>(std::move(reader));
}

}  // namespace

StatusOr<std::unique_ptr<SensorBagReader>> OpenSensorStream(const std::string& path,
                                                            const LidarOptions& lidar,
                                                            const ImuOptions& imu,
                                                            const ReadWindow& window,
                                                            const ReaderOptions& io) {
  StatusOr<std::unique_ptr<SensorBagReader>> inner = SensorBagReader::Open(path, lidar, imu);
  if (!inner.ok()) return inner.status();
  TimeNs first_receive_ns = 0;
  if (Status s = CheckWindow(path, window, &first_receive_ns); !s.ok()) return s;
  std::optional<TimeNs> first_ns;
  if (window.start_s > 0.0) {
    StatusOr<std::unique_ptr<SensorBagReader>> skipping =
        SkipAhead(path, lidar, imu, window, first_receive_ns, inner->get(), &first_ns);
    if (!skipping.ok()) return skipping.status();
    if (*skipping) inner = std::move(skipping);
  }
  std::unique_ptr<SensorBagReader> reader = std::make_unique<WindowedReader>(
      std::move(inner).value(), lidar.time_offset, window, first_ns);
  if (io.reader_thread) reader = std::make_unique<ThreadedReader>(std::move(reader), io);
  return reader;
}

}  // namespace rvlio
