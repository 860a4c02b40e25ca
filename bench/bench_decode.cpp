// Bag decoding per scan: DecodePointCloud2 on one in-memory OS1-32 message
// (32 x 1024, the Ouster driver layout the simulator writes, organized with
// zero points for no-returns), and reading a small simulated recording through
// the SensorBagReader (container reading + message deserialization + decode)
// for every kind of recording: ROS1 bag, MCAP (chunks uncompressed, zstd,
// lz4) and db3, reported per iteration of 20 scans. Neither is inside
// `rvlio run`'s per-scan time: the reader decodes the next scan before the
// estimator sees it.
//
// BM_ReadMcap/<compression> reads the same 20 sweeps + 400 IMU-sized
// payloads from an MCAP file (formats/mcap.h) with chunks uncompressed, zstd and
// lz4: the container's cost per message (decompression, CRC, copy; no CDR
// decoding).
//
// BM_DecompressChunks/<kind> is the floor under the compressed kinds: the
// chunks of BM_ReadBagPerScan's zstd (2) and lz4 (3) recordings decompressed
// alone (libzstd / liblz4 into one reused buffer; no CRC, no parsing). The
// reading cost of a compressed recording is this + the reader's own work.
//
// BM_Crc32/<0|1>: the CRC-32 the MCAP reader checks on every chunk
// (src/formats/mcap_records.h, libdeflate) and, for reference, zlib's crc32 on
// the same 32 MiB.
//
//   build/bin/bench_decode --benchmark_filter='BM_ReadMcap|BM_ReadBag|BM_Decompress|BM_Crc32'
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <benchmark/benchmark.h>
#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "../src/formats/mcap_records.h"
#include "rvlio/formats/mcap.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

constexpr int kRows = 32;
constexpr int kCols = 1024;
constexpr uint32_t kPointStep = 48;  // x y z . intensity t reflectivity ring ambient range .

// Range from o along d to the walls of a 200 x 8 x 5 m box tunnel; rays that
// travel farther than 60 m are no-returns (0).
double BoxRange(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-100.0, -4.0, 0.0), hi(100.0, 4.0, 5.0);
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (d(a) > 1e-12) t = std::min(t, (hi(a) - o(a)) / d(a));
    if (d(a) < -1e-12) t = std::min(t, (lo(a) - o(a)) / d(a));
  }
  return t > 60.0 ? 0.0 : t;
}

// One organized sweep (row-major by ring), times 0..100 ms over the columns.
Scan Sweep(std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::Vector3d o(0.0, 0.5, 2.0);
  Scan scan;
  scan.t_start_ns = 1700000000000000000LL;
  scan.t_end_ns = scan.t_start_ns + 99902343;
  for (int b = 0; b < kRows; ++b) {
    const double e = (-22.5 + 45.0 * b / (kRows - 1)) * M_PI / 180;
    for (int c = 0; c < kCols; ++c) {
      const double a = 2 * M_PI * c / kCols;
      const Eigen::Vector3d d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      const double r = BoxRange(o, d);
      LidarPoint p;
      if (r > 0.0) p.p_lidar = ((r + noise(*rng)) * d).cast<float>();
      p.intensity = 100.0f;
      p.t_ns = scan.t_start_ns + (c * 100000000LL) / kCols;
      p.ring = static_cast<uint16_t>(b);
      scan.points.push_back(p);
    }
  }
  return scan;
}

template <class T>
void Put(uint8_t* dst, uint32_t offset, T value) {
  std::memcpy(dst + offset, &value, sizeof(T));
}

struct Message {
  std::vector<uint8_t> data;
  PointCloud2View view;
};

Message OusterMessage(const Scan& scan) {
  Message m;
  m.data.assign(scan.points.size() * kPointStep, 0);
  for (size_t i = 0; i < scan.points.size(); ++i) {
    const LidarPoint& p = scan.points[i];
    uint8_t* dst = m.data.data() + i * kPointStep;
    Put<float>(dst, 0, p.p_lidar.x());
    Put<float>(dst, 4, p.p_lidar.y());
    Put<float>(dst, 8, p.p_lidar.z());
    Put<float>(dst, 16, p.intensity);
    Put<uint32_t>(dst, 20, static_cast<uint32_t>(p.t_ns - scan.t_start_ns));
    Put<uint16_t>(dst, 26, p.ring);
    Put<uint32_t>(dst, 32, static_cast<uint32_t>(1000.0f * p.p_lidar.norm()));
  }
  PointCloud2View& v = m.view;
  v.header_stamp_ns = scan.t_start_ns;
  v.height = kRows;
  v.width = kCols;
  v.point_step = kPointStep;
  v.row_step = kPointStep * kCols;
  v.fields = {{"x", 0, kPointFloat32, 1},         {"y", 4, kPointFloat32, 1},
              {"z", 8, kPointFloat32, 1},         {"intensity", 16, kPointFloat32, 1},
              {"t", 20, kPointUint32, 1},         {"reflectivity", 24, kPointUint16, 1},
              {"ring", 26, kPointUint16, 1},      {"ambient", 28, kPointUint16, 1},
              {"range", 32, kPointUint32, 1}};
  v.data = m.data.data();
  v.data_size = m.data.size();
  v.topic = "/os_cloud_node/points";
  return m;
}

// BM_DecodePointCloud2/<0|1>: the OS1-32 1024-column message through the
// generic reader (0, DecodePointCloud2Generic) and the fast path of the
// common layouts (1, DecodePointCloud2); both return the same scan.
void BM_DecodePointCloud2(benchmark::State& state) {
  std::mt19937 rng(1);
  const Message m = OusterMessage(Sweep(&rng));
  LidarOptions lidar;
  lidar.type = "ouster";
  DecodeStats stats;
  const bool fast = state.range(0) == 1;
  for (auto _ : state) {
    StatusOr<Scan> scan = fast ? DecodePointCloud2(m.view, lidar, &stats)
                               : DecodePointCloud2Generic(m.view, lidar, &stats);
    benchmark::DoNotOptimize(scan.ok());
  }
  state.counters["raw_points"] = static_cast<double>(stats.raw_points);
  state.counters["invalid"] = static_cast<double>(stats.invalid_points);
  state.counters["fast_path"] = stats.fast_path ? 1.0 : 0.0;
}
BENCHMARK(BM_DecodePointCloud2)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// A 2 s recording: 20 scans of the sweep above and 200 Hz IMU, written once
// per kind through SensorBagWriter (the simulator's writer), so every kind
// holds the same messages.
struct RecordingKind {
  const char* name;         // label and file name part
  const char* format;       // BagWriterOptions::format
  const char* compression;  // BagWriterOptions::mcap_compression
  const char* extension;
};
constexpr RecordingKind kRecordingKinds[] = {
    {"ros1 bag", "ros1", "", ".bag"},
    {"mcap chunks uncompressed", "mcap", "none", ".mcap"},
    {"mcap chunks zstd", "mcap", "zstd", ".mcap"},
    {"mcap chunks lz4", "mcap", "lz4", ".mcap"},
    {"db3 (sqlite3)", "db3", "", ".db3"},
};

// A temporary file of this process, removed when it goes; ok() once the
// derived class has written it completely (Finish).
class TempFile {
 public:
  explicit TempFile(const std::string& stem)
      : path_((std::filesystem::temp_directory_path() /
               ("rvlio_bench_decode_" + std::to_string(::getpid()) + "_" + stem))
                  .string()) {}
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() { std::filesystem::remove(path_); }
  bool ok() const { return ok_; }
  const std::string& path() const { return path_; }
  uint64_t bytes() const { return bytes_; }

 protected:
  void Finish(bool closed) {
    ok_ = closed;
    bytes_ = ok_ ? std::filesystem::file_size(path_) : 0;
  }
  const std::string path_;

 private:
  bool ok_ = false;
  uint64_t bytes_ = 0;
};

class BagFile : public TempFile {
 public:
  static constexpr int kScans = 20;
  explicit BagFile(const RecordingKind& kind)
      : TempFile(std::string(kind.format) + kind.compression + kind.extension) {
    std::mt19937 rng(1);
    Scan scan = Sweep(&rng);
    BagWriterOptions options;
    options.format = kind.format;
    if (*kind.compression != '\0') options.mcap_compression = kind.compression;
    auto writer = SensorBagWriter::Create(path_, options);
    if (!writer.ok()) return;
    const LidarOptions lidar;
    const ImuOptions imu_options;
    for (int k = 0; k < kScans; ++k) {
      for (int j = 0; j < 20; ++j) {
        ImuSample imu;
        imu.t_ns = scan.t_start_ns + j * 5000000LL;
        imu.acc_imu = Eigen::Vector3d(0.0, 0.0, 9.81);
        (void)(*writer)->WriteImu(imu_options.topic, "imu", imu);
      }
      (void)(*writer)->WriteOusterScan(lidar.topic, "os_sensor", scan, kRows, kCols);
      for (LidarPoint& p : scan.points) p.t_ns += 100000000LL;
      scan.t_start_ns += 100000000LL;
      scan.t_end_ns += 100000000LL;
    }
    Finish((*writer)->Close().ok());
  }
};

// Read + decode every scan of the recording through the public reading path
// (SensorBagReader::Open, Next), the same for every kind of recording.
// Wall time ("Time") and the CPU time of the whole process ("CPU", worker
// threads included) are both reported.
void BM_ReadBagPerScan(benchmark::State& state) {
  const RecordingKind& kind = kRecordingKinds[state.range(0)];
  const BagFile bag(kind);
  if (!bag.ok()) {
    state.SkipWithError("could not write the temporary recording");
    return;
  }
  int64_t scans = 0;
  for (auto _ : state) {
    auto reader = SensorBagReader::Open(bag.path(), LidarOptions(), ImuOptions());
    if (!reader.ok()) {
      state.SkipWithError(reader.status().message().c_str());
      return;
    }
    ImuSample imu;
    Scan scan;
    for (;;) {
      StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
      if (!m.ok()) {
        state.SkipWithError(m.status().message().c_str());
        return;
      }
      if (*m == SensorMessage::kEnd) break;
      scans += *m == SensorMessage::kScan ? 1 : 0;
    }
  }
  // items = scans: items_per_second is scans per second.
  state.SetItemsProcessed(scans);
  state.counters["file_MB"] = static_cast<double>(bag.bytes()) / 1e6;
  state.SetLabel(std::string(kind.name) + ", 20 scans + 400 IMU samples per iteration");
}
BENCHMARK(BM_ReadBagPerScan)
    ->DenseRange(0, 4)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

uint64_t LeField(const std::string& b, size_t at, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t{static_cast<uint8_t>(b[at + i])} << (8 * i);
  return v;
}

// The compressed records of every Chunk record of an MCAP file (top-level
// walk from the specification: opcode, uint64 length, content; a chunk's
// content is start, end, uncompressed size (uint64 each), CRC (uint32),
// compression (string), records (uint64 length + bytes)). Empty on a file it
// cannot walk.
std::vector<std::string> ChunkRecords(const std::string& path, uint64_t* uncompressed_bytes) {
  std::string b;
  if (FILE* f = std::fopen(path.c_str(), "rb")) {
    char buf[1 << 16];
    for (size_t n; (n = std::fread(buf, 1, sizeof(buf), f)) > 0;) b.append(buf, n);
    std::fclose(f);
  }
  std::vector<std::string> chunks;
  *uncompressed_bytes = 0;
  for (size_t pos = 8; pos + 9 <= b.size();) {
    const size_t content = pos + 9, end = content + LeField(b, pos + 1, 8);
    if (end > b.size() || end < content) return {};
    if (b[pos] == 0x06) {
      *uncompressed_bytes += LeField(b, content + 16, 8);
      const size_t name = content + 28, records = name + 4 + LeField(b, name, 4);
      if (records + 8 > end) return {};
      chunks.push_back(b.substr(records + 8, LeField(b, records, 8)));
    }
    pos = end;
  }
  return chunks;
}

// Decompresses `in` (zstd frame or LZ4 frame) into `out` (sized to the
// uncompressed size by the caller); false on a decoder error.
bool DecompressChunk(const std::string& in, bool zstd, ZSTD_DCtx* zctx, LZ4F_dctx* lctx,
                     std::string* out) {
  if (zstd) {
    const size_t n = ZSTD_decompressDCtx(zctx, &(*out)[0], out->size(), in.data(), in.size());
    return !ZSTD_isError(n);
  }
  size_t dst = out->size(), src = in.size();
  const size_t r = LZ4F_decompress(lctx, &(*out)[0], &dst, in.data(), &src, nullptr);
  return r == 0 && src == in.size();
}

void BM_DecompressChunks(benchmark::State& state) {
  const RecordingKind& kind = kRecordingKinds[state.range(0)];
  const BagFile bag(kind);
  uint64_t uncompressed = 0;
  const std::vector<std::string> chunks = bag.ok() ? ChunkRecords(bag.path(), &uncompressed)
                                                   : std::vector<std::string>();
  const bool zstd = std::string(kind.compression) == "zstd";
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> zctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
  LZ4F_dctx* raw = nullptr;
  LZ4F_createDecompressionContext(&raw, LZ4F_VERSION);
  std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> lctx(
      raw, LZ4F_freeDecompressionContext);
  if (chunks.empty() || !zctx || !lctx) {
    state.SkipWithError("could not write or walk the temporary recording");
    return;
  }
  std::string out(uncompressed, '\0');  // more than any chunk needs
  for (auto _ : state) {
    for (const std::string& chunk : chunks) {
      if (!DecompressChunk(chunk, zstd, zctx.get(), lctx.get(), &out)) {
        state.SkipWithError("decompression failed");
        return;
      }
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * uncompressed));
  state.counters["chunks"] = static_cast<double>(chunks.size());
  state.SetLabel(std::string(kind.name) + ", decompression alone");
}
BENCHMARK(BM_DecompressChunks)
    ->Arg(2)
    ->Arg(3)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

void BM_Crc32(benchmark::State& state) {
  std::string bytes(32 << 20, '\0');
  std::mt19937 rng(1);
  for (char& c : bytes) c = static_cast<char>(rng());
  const bool zlib = state.range(0) == 1;
  for (auto _ : state) {
    const uint32_t crc =
        zlib ? static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(bytes.data()),
                                           static_cast<uInt>(bytes.size())))
             : mcap::detail::Crc32(bytes);
    benchmark::DoNotOptimize(crc);
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
  state.SetLabel(zlib ? "zlib crc32 (reference)" : "Crc32 (libdeflate), as the MCAP reader");
}
BENCHMARK(BM_Crc32)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The sweep message of BM_DecodePointCloud2 20 times and 400 IMU-sized
// (300-byte) payloads, as an MCAP file with chunk compression `compression`.
class McapFile : public TempFile {
 public:
  explicit McapFile(const std::string& compression)
      : TempFile((compression.empty() ? "none" : compression) + ".mcap") {
    std::mt19937 rng(1);
    const Message cloud = OusterMessage(Sweep(&rng));
    mcap::WriterOptions options;
    options.compression = compression;
    auto writer = mcap::Writer::Create(path_, options);
    if (!writer.ok()) return;
    auto schema = (*writer)->AddSchema("sensor_msgs/msg/PointCloud2", "ros2msg", "");
    auto imu_schema = (*writer)->AddSchema("sensor_msgs/msg/Imu", "ros2msg", "");
    if (!schema.ok() || !imu_schema.ok()) return;
    auto lidar = (*writer)->AddChannel(*schema, "/points", "cdr");
    auto imu = (*writer)->AddChannel(*imu_schema, "/imu", "cdr");
    if (!lidar.ok() || !imu.ok()) return;
    uint64_t t_ns = 1700000000000000000ull;
    for (int k = 0; k < 20; ++k) {
      for (int j = 0; j < 20; ++j) {
        mcap::Message m{*imu, 0, t_ns + j * 5000000ull, 0, std::vector<uint8_t>(300, uint8_t(j))};
        if (!(*writer)->Write(m).ok()) return;
      }
      if (!(*writer)->Write(mcap::Message{*lidar, 0, t_ns, 0, cloud.data}).ok()) return;
      t_ns += 100000000ull;
    }
    Finish((*writer)->Close().ok());
  }
};

void BM_ReadMcap(benchmark::State& state) {
  static const char* kCompressions[] = {"", "zstd", "lz4"};
  const std::string compression = kCompressions[state.range(0)];
  const McapFile file(compression);
  if (!file.ok()) {
    state.SkipWithError("could not write the temporary MCAP file");
    return;
  }
  int64_t messages = 0, payload_bytes = 0;
  for (auto _ : state) {
    auto reader = mcap::Reader::Open(file.path());
    if (!reader.ok()) {
      state.SkipWithError(reader.status().message().c_str());
      return;
    }
    mcap::Message m;
    for (;;) {
      StatusOr<bool> more = (*reader)->Next(&m);
      if (!more.ok() || !*more) break;
      ++messages;
      payload_bytes += static_cast<int64_t>(m.data.size());
    }
  }
  // items = messages (20 sweeps + 400 IMU payloads per iteration).
  state.SetItemsProcessed(messages);
  state.SetBytesProcessed(payload_bytes);
  state.counters["file_MB"] = static_cast<double>(file.bytes()) / 1e6;
  state.SetLabel(compression.empty() ? "chunks uncompressed" : "chunks " + compression);
}
BENCHMARK(BM_ReadMcap)
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
}  // namespace rvlio

BENCHMARK_MAIN();
