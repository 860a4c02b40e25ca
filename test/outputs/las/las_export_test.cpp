// `rvlio export` and its pieces: PointCloudStream (formats/point_cloud_file.h)
// reads what ReadPointCloud reads, chunk by chunk; ExportPointCloudToLas
// (outputs/map_las.h) puts every PCD field where docs/outputs.md says, equals
// run's map.las for run's map.pcd, refuses bad input with one line and leaves
// nothing behind, and streams in bounded memory; the command's exit codes.
#include <cmath>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "las_test_util.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/outputs/map_las.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio {
namespace {

using las_test::At;
using las_test::PcdField;
using las_test::ReadBytes;
using las_test::ScratchDir;
using las_test::WritePcd;

const std::vector<PcdField> kMapFields = {
    {"x", 'F', 8},         {"y", 'F', 8},           {"z", 'F', 4},
    {"intensity", 'F', 4}, {"time", 'F', 8},        {"ring", 'U', 2},
    {"deviation_m", 'F', 4}, {"scan_index", 'U', 4}, {"range_m", 'F', 4}};

// Survey-sized points with every attribute of kMapFields.
std::vector<std::vector<double>> MapRows(int n) {
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < n; ++i)
    rows.push_back({500000.0 + 0.013 * i, 5400000.0 + 0.007 * i, 12.5 + 0.001 * (i % 97),
                    static_cast<double>(i % 251), 1.7e9 + 1e-4 * i + 1.25e-7, static_cast<double>(i % 64),
                    i % 5 == 0 ? std::nan("") : 0.001 * (i % 41) - 0.02, static_cast<double>(i / 100),
                    1.0 + i % 30});
  return rows;
}

StatusOr<std::vector<std::vector<double>>> StreamAll(const std::string& path, size_t chunk) {
  PointCloudStream s;
  if (Status st = s.Open(path); !st.ok()) return st;
  std::vector<std::vector<double>> rows;
  PointCloudChunk c;
  for (;;) {
    StatusOr<size_t> n = s.Read(chunk, &c);
    if (!n.ok()) return n.status();
    if (*n == 0) return rows;
    for (size_t i = 0; i < *n; ++i) {
      std::vector<double> row = {c.points[i].x(), c.points[i].y(), c.points[i].z()};
      for (const auto& f : c.fields) row.push_back(f[i]);
      rows.push_back(row);
    }
  }
}

TEST(PointCloudStream, ReadsWhatReadPointCloudReadsInAnyChunkSize) {
  ScratchDir dir;
  const auto rows = MapRows(3000);
  for (bool binary : {true, false}) {
    const std::string path = dir.Path(binary ? "b.pcd" : "a.pcd");
    WritePcd(path, kMapFields, rows, binary);
    StatusOr<PointCloudFile> whole = ReadPointCloud(path);
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    for (size_t chunk : {1, 7, 4096}) {
      StatusOr<std::vector<std::vector<double>>> got = StreamAll(path, chunk);
      ASSERT_TRUE(got.ok()) << got.status().message();
      ASSERT_EQ(got->size(), rows.size());
      for (size_t i = 0; i < rows.size(); ++i) {
        ASSERT_EQ((*got)[i][0], whole->points[i].x()) << i;
        ASSERT_EQ((*got)[i][2], whole->points[i].z()) << i;
        for (size_t k = 0; k < whole->fields.size(); ++k) {
          const double v = (*got)[i][3 + k];
          const float w = whole->fields[k].values[i];
          if (std::isnan(w)) ASSERT_TRUE(std::isnan(v)) << i << " " << k;
          else ASSERT_EQ(static_cast<float>(v), w) << i << " " << k;
        }
        // The stream keeps doubles: the F8 time to the ns (a float keeps 128 s).
        ASSERT_NEAR((*got)[i][4], rows[i][4], binary ? 0.0 : 1e-6) << i;
      }
    }
  }
}

TEST(PointCloudStream, AsciiNumbersCutByTheReadBlocksAreReadWhole) {
  ScratchDir dir;
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 60000; ++i)  // about 2.4 MB: words cross the 1 MiB blocks
    rows.push_back({i * 1.234567891, -i * 0.5, 1e-3 * i, 1.0 / (i + 3)});
  const std::string path = dir.Path("big_ascii.pcd");
  WritePcd(path, {{"x", 'F', 4}, {"y", 'F', 4}, {"z", 'F', 4}, {"w", 'F', 4}}, rows, false);
  StatusOr<std::vector<std::vector<double>>> got = StreamAll(path, 999);
  ASSERT_TRUE(got.ok()) << got.status().message();
  ASSERT_EQ(got->size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i)
    for (int k = 0; k < 4; ++k) ASSERT_NEAR((*got)[i][k], rows[i][k], 1e-12 * (1 + std::abs(rows[i][k]))) << i;
}

TEST(LasExport, EveryPcdFieldGoesToItsLasField) {
  ScratchDir dir;
  const auto rows = MapRows(500);
  WritePcd(dir.Path("map.pcd"), kMapFields, rows, true);
  LasExportOptions o;
  o.crs = "EPSG:25832";
  StatusOr<LasExportResult> r = ExportPointCloudToLas(dir.Path("map.pcd"), dir.Path("map.las"), o);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->stats.points, 500u);
  EXPECT_EQ(r->intensity_field, "intensity");
  EXPECT_EQ(r->intensity_range, 256.0) << "largest 250: an 8-bit range";
  EXPECT_EQ(r->time_field, "time");
  EXPECT_EQ(r->ring_field, "ring");
  EXPECT_EQ(r->extra_fields, (std::vector<std::string>{"deviation_m", "scan_index", "range_m"}));
  const std::string b = ReadBytes(dir.Path("map.las"));
  EXPECT_EQ(At<uint16_t>(b, 105), 30 + 4 + 4 + 4);
  EXPECT_EQ(At<double>(b, 155), 500000.0);
  EXPECT_EQ(At<double>(b, 163), 5400000.0);
  const uint32_t start = At<uint32_t>(b, 96);
  for (size_t i = 0; i < rows.size(); ++i) {
    const size_t p = start + 42 * i;
    EXPECT_NEAR(At<int32_t>(b, p) * 0.001 + 500000.0, rows[i][0], 5e-4 + 1e-9);
    EXPECT_NEAR(At<int32_t>(b, p + 4) * 0.001 + 5400000.0, rows[i][1], 5e-4 + 1e-9);
    EXPECT_EQ(At<uint16_t>(b, p + 12), rows[i][3] * 256.0);
    EXPECT_EQ(At<uint8_t>(b, p + 17), rows[i][5]);
    EXPECT_EQ(At<uint16_t>(b, p + 20), rows[i][7]) << "point source ID: the scan index";
    EXPECT_NEAR(At<double>(b, p + 22), rows[i][4] - 315964800.0 + 18.0 - 1e9, 1e-6);
    const float dev = At<float>(b, p + 30);
    if (std::isnan(rows[i][6])) EXPECT_TRUE(std::isnan(dev));
    else EXPECT_EQ(dev, static_cast<float>(rows[i][6]));
    EXPECT_EQ(At<uint32_t>(b, p + 34), rows[i][7]);
    EXPECT_EQ(At<float>(b, p + 38), static_cast<float>(rows[i][8]));
  }
  EXPECT_NE(b.find("AUTHORITY[\"EPSG\",\"25832\"]"), std::string::npos);
}

TEST(LasExport, IntensityRangeFollowsTheLargestValueUnlessGiven) {
  ScratchDir dir;
  const struct { double largest, given, range; } kCases[] = {
      {0.8, 0, 1}, {200, 0, 256}, {4000, 0, 65536}, {70000.5, 0, 70001}, {200, 65536, 65536}};
  for (const auto& c : kCases) {
    WritePcd(dir.Path("i.pcd"), {{"x", 'F', 4}, {"y", 'F', 4}, {"z", 'F', 4}, {"intensity", 'F', 4}},
             {{0, 0, 0, 0.0}, {1, 0, 0, c.largest}}, true);
    LasExportOptions o;
    o.intensity_range = c.given;
    StatusOr<LasExportResult> r = ExportPointCloudToLas(dir.Path("i.pcd"), dir.Path("i.las"), o);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->intensity_range, c.range) << c.largest;
    const std::string b = ReadBytes(dir.Path("i.las"));
    EXPECT_EQ(At<uint16_t>(b, At<uint32_t>(b, 96) + 30 + 12),
              std::min(65535.0, std::nearbyint(static_cast<float>(c.largest) * 65536.0 / c.range)));
  }
}

TEST(LasExport, AFloatTimeIsKeptAsExtraBytesNotAsGpsTime) {
  ScratchDir dir;
  WritePcd(dir.Path("t.pcd"), {{"x", 'F', 4}, {"y", 'F', 4}, {"z", 'F', 4}, {"t", 'F', 4}},
           {{0, 0, 0, 0.05}}, true);
  StatusOr<LasExportResult> r = ExportPointCloudToLas(dir.Path("t.pcd"), dir.Path("t.las"), {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->time_field, "");
  EXPECT_EQ(r->extra_fields, std::vector<std::string>{"t"});
}

TEST(LasExport, RunsMapPcdExportsToTheSameFileAsRunsMapLas) {
  ScratchDir dir;
  // A map as run writes it: every attribute, and deviation_m with NaNs.
  MapCloud map;
  map.has_intensity = map.has_time = map.has_ring = map.has_scan_index = true;
  std::vector<double> deviation;
  for (int i = 0; i < 2000; ++i) {
    // Half millimetres: a float32 and a double often round to different mm.
    map.p.emplace_back(0.0010001 * i + 0.0005 - 3.0, std::sin(0.01 * i), 12.3455 + 0.001 * i);
    map.intensity.push_back(static_cast<float>((i * 37) % 200) + 0.25f);
    map.t_ns.push_back(1'700'000'000'123'456'789 + 123'457LL * i);
    map.ring.push_back(static_cast<uint16_t>(i % 128));
    map.scan_index.push_back(static_cast<uint32_t>(i / 7));
    deviation.push_back(i % 7 == 0 ? std::nan("") : 0.0001 * i);
  }
  ASSERT_TRUE(WriteMapPcd(dir.Path("map.pcd"), map, &deviation).ok());
  // Small chunks: the chunking does not show in the file.
  ASSERT_TRUE(WriteMapLas(dir.Path("run.las"), map, &deviation, "", 300).ok());
  StatusOr<LasExportResult> r = ExportPointCloudToLas(dir.Path("map.pcd"), dir.Path("export.las"), {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->intensity_field, "intensity");
  EXPECT_EQ(r->time_field, "time");
  EXPECT_EQ(r->ring_field, "ring");
  EXPECT_EQ(r->extra_fields, (std::vector<std::string>{"scan_index", "deviation_m"}));
  std::string a = ReadBytes(dir.Path("run.las")), b = ReadBytes(dir.Path("export.las"));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 90; i < 94; ++i) a[i] = b[i] = 0;  // the creation day and year
  EXPECT_TRUE(a == b);
}

TEST(LasExport, BadInputIsOneLineNamingTheFileAndLeavesNothing) {
  ScratchDir dir;
  const auto rows = MapRows(50);
  WritePcd(dir.Path("good.pcd"), kMapFields, rows, true);
  const std::string good = ReadBytes(dir.Path("good.pcd"));
  std::ofstream(dir.Path("truncated.pcd"), std::ios::binary) << good.substr(0, good.size() - 10);
  std::ofstream(dir.Path("garbage.pcd"), std::ios::binary) << "hello, not a point cloud\n";
  std::ofstream(dir.Path("compressed.pcd"), std::ios::binary)
      << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_compressed\n";
  std::ofstream(dir.Path("cloud.ply"), std::ios::binary)
      << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n1 2 3\n";
  std::ofstream(dir.Path("nan.pcd"), std::ios::binary)
      << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\nnan 2 3\n";
  std::ofstream(dir.Path("word.pcd"), std::ios::binary)
      << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 2\nDATA ascii\n1 2 3\n4 five 6\n";
  std::ofstream(dir.Path("a_file"), std::ios::binary) << "x";
  std::ofstream(dir.Path("huge.pcd"), std::ios::binary)
      << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4294967296\nHEIGHT 4294967296\nDATA binary\n";
  std::ofstream(dir.Path("long.pcd"), std::ios::binary)
      << "FIELDS x y z " << std::string(33, 'f') << "\nSIZE 4 4 4 4\nTYPE F F F F\nPOINTS 1\nDATA ascii\n1 2 3 4\n";
  std::ofstream(dir.Path("twice.pcd"), std::ios::binary)
      << "FIELDS x y z w w\nSIZE 4 4 4 4 4\nTYPE F F F F F\nPOINTS 1\nDATA ascii\n1 2 3 4 5\n";
  const struct { std::string map, out, crs; StatusCode code; std::string says; } kBad[] = {
      {dir.Path("missing.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "missing.pcd: cannot open"},
      {dir.Path("truncated.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "truncated"},
      {dir.Path("garbage.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "garbage.pcd: not a PCD"},
      {dir.Path("compressed.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "binary_compressed"},
      {dir.Path("cloud.ply"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "PLY"},
      {dir.Path("nan.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "point 1 has a non-finite"},
      {dir.Path("word.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "'five' is not a number"},
      {dir.dir().string(), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "is a directory"},
      {dir.Path("huge.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "WIDTH x HEIGHT overflows"},
      {dir.Path("long.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "long.pcd: field 'fff"},
      {dir.Path("twice.pcd"), dir.Path("o.las"), "local", StatusCode::kInvalidInput, "twice.pcd: field w appears twice"},
      {dir.Path("good.pcd"), dir.Path("o.las"), "EPSG:99999999", StatusCode::kInvalidInput, "survey.crs 'EPSG:99999999'"},
      {dir.Path("good.pcd"), dir.Path("o.laz"), "local", StatusCode::kInvalidInput, "must be a .las file"},
      {dir.Path("good.pcd"), dir.Path("a_file/o.las"), "local", StatusCode::kInvalidInput, "Not a directory"},
      {dir.Path("good.pcd"), dir.Path("no/such/o.las"), "local", StatusCode::kIoError, "cannot write"},
      {dir.Path("good.pcd"), dir.dir().string() + "/.las", "local", StatusCode::kInvalidInput, ""},
  };
  const std::vector<std::string> before = dir.Files();
  for (const auto& c : kBad) {
    LasExportOptions o;
    o.crs = c.crs;
    StatusOr<LasExportResult> r = ExportPointCloudToLas(c.map, c.out, o);
    ASSERT_FALSE(r.ok()) << c.map << " -> " << c.out;
    EXPECT_EQ(r.status().code(), c.code) << r.status().message();
    EXPECT_NE(r.status().message().find(c.says), std::string::npos) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
    EXPECT_EQ(dir.Files(), before) << "something was left by " << c.map << " -> " << c.out;
  }
  // The input named as the output is refused and stays as it was.
  StatusOr<LasExportResult> same = ExportPointCloudToLas(dir.Path("good.pcd"), dir.Path("good.pcd"), {});
  EXPECT_FALSE(same.ok());
  std::filesystem::copy_file(dir.Path("good.pcd"), dir.Path("map.las"));
  same = ExportPointCloudToLas(dir.Path("map.las"), dir.dir().string() + "/./map.las", {});
  ASSERT_FALSE(same.ok());
  EXPECT_NE(same.status().message().find("is the input map"), std::string::npos) << same.status().message();
  EXPECT_EQ(ReadBytes(dir.Path("map.las")), good);
}

TEST(LasExport, AMapOfMillionsOfPointsIsExportedInBoundedMemory) {
  ScratchDir dir;
  const int n = 2'000'000;
  {  // a binary PCD of x y z intensity (32 MB), written in blocks
    std::ofstream out(dir.Path("big.pcd"), std::ios::binary);
    out << "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nPOINTS " << n << "\nDATA binary\n";
    std::vector<float> block;
    for (int i = 0; i < n; ++i) {
      block.insert(block.end(), {0.001f * i, 0.5f * (i % 1000), 2.0f, static_cast<float>(i % 256)});
      if (block.size() >= 4 * 65536 || i + 1 == n) {
        out.write(reinterpret_cast<const char*>(block.data()), block.size() * sizeof(float));
        block.clear();
      }
    }
  }
  if (!las_test::ResetPeakRss()) GTEST_SKIP() << "the kernel does not reset the peak RSS";
  const long before_kb = las_test::PeakRssKb();
  StatusOr<LasExportResult> r = ExportPointCloudToLas(dir.Path("big.pcd"), dir.Path("big.las"), {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->stats.points, static_cast<uint64_t>(n));
  EXPECT_LT(las_test::PeakRssKb() - before_kb, 24 * 1024)
      << "the export holds the map instead of streaming it (" << n << " points: "
      << n * 32 / 1024 / 1024 << " MB as doubles)";
}

TEST(ExportCli, WritesTheFileAndRefusesBadInputWithExitTwo) {
  ScratchDir dir;
  WritePcd(dir.Path("map.pcd"), kMapFields, MapRows(20), false);
  const std::string scratch = dir.dir().string();
  using testing_cli::RunTool;
  testing_cli::ToolRun ok =
      RunTool("export --map " + dir.Path("map.pcd") + " --out " + dir.Path("map.las") +
                  " --crs EPSG:25832",
              scratch);
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("20 points -> " + dir.Path("map.las")), std::string::npos) << ok.out;
  EXPECT_TRUE(std::filesystem::exists(dir.Path("map.las")));
  const struct { std::string args, says; } kBad[] = {
      {"--map " + dir.Path("nope.pcd") + " --out " + dir.Path("x.las"), "nope.pcd"},
      {"--map " + dir.Path("map.pcd") + " --out " + dir.Path("x.las") + " --crs EPSG:0", "EPSG:0"},
      {"--map " + dir.Path("map.pcd") + " --out /proc/x.las", "/proc/x.las"},
      {"--map " + dir.Path("map.pcd") + " --out " + dir.Path("x.las") + " --intensity-range 0", "--intensity-range"},
      {"--map " + dir.Path("map.pcd"), "--out"},
  };
  for (const auto& c : kBad) {
    testing_cli::ToolRun r = RunTool("export " + c.args, scratch);
    testing_cli::ExpectOneErrorLine(r, "export", c.says);
    EXPECT_FALSE(std::filesystem::exists(dir.Path("x.las")));
  }
}

}  // namespace
}  // namespace rvlio
