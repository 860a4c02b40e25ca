// `rvlio report`'s data extraction (rvlio/experiments/report_data.h, its
// model src/experiments/report_model.h) and page assembly (apps/report_html.h)
// on folders built here with known contents.
#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "report_html.h"
#include "report_model.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/outputs/summary_json.h"

namespace rvlio::experiments::report {
namespace {

using cli::report::RenderReportHtml;
using cli::report::WriteReport;
using cli::report::WrittenReport;

namespace fs = std::filesystem;
using nlohmann::json;

// The page's decoding (report.js decode), written independently: base64 ->
// little-endian float32.
std::vector<float> DecodeArray(const std::string& b64) {
  auto sextet = [](char c) -> uint32_t {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : 63;
  };
  std::vector<uint8_t> bytes;
  for (size_t i = 0; i + 3 < b64.size(); i += 4) {
    uint32_t v = 0;
    int pad = 0;
    for (int k = 0; k < 4; ++k) {
      pad += b64[i + k] == '=' ? 1 : 0;
      v = (v << 6) | (b64[i + k] == '=' ? 0 : sextet(b64[i + k]));
    }
    for (int k = 0; k < 3 - pad; ++k) bytes.push_back(static_cast<uint8_t>(v >> (16 - 8 * k)));
  }
  std::vector<float> out(bytes.size() / 4);
  for (size_t i = 0; i < out.size(); ++i) {
    const uint32_t u = bytes[4 * i] | bytes[4 * i + 1] << 8 | bytes[4 * i + 2] << 16 |
                       static_cast<uint32_t>(bytes[4 * i + 3]) << 24;
    std::memcpy(&out[i], &u, 4);
  }
  return out;
}

class ReportDataTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "rvlio_report_XXXXXX").string();
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Path(const std::string& rel) const { return (fs::path(dir_) / rel).string(); }
  void Write(const std::string& rel, const std::string& text) const {
    fs::create_directories(fs::path(Path(rel)).parent_path());
    std::ofstream(Path(rel), std::ios::binary) << text;
  }

  // A straight 20 m path along x over 10 s at 10 Hz, as ground truth.
  static Trajectory Straight(double offset_y) {
    Trajectory t;
    for (int k = 0; k <= 100; ++k) {
      StampedPose p;
      p.t_ns = 1000000000LL + 100000000LL * k;
      p.p_world_imu = Eigen::Vector3d(0.2 * k, offset_y + 0.01 * std::sin(0.3 * k), 1.0);
      p.q_world_imu = Eigen::Quaterniond::Identity();
      t.push_back(p);
    }
    return t;
  }

  // A run folder: trajectory, scans.csv (two scans), summary.json, map.pcd
  // with `points` points, optionally with a deviation_m field (value =
  // 0.001 i) and an intensity field (3 i).
  void WriteRun(const std::string& rel, const Trajectory& est, size_t points, bool deviation) {
    fs::create_directories(Path(rel));
    ASSERT_TRUE(WriteTum(Path(rel + "/trajectory.tum"), est).ok());
    Write(rel + "/scans.csv",
          "t,status,rv_active,coplanar_fraction,nis,residual_rms_m,diverged\n"
          "1.0,ok,0,0.5,1.2,0.02,\n1.1,ok,1,0.75,,0.03,nis\n");
    Write(rel + "/summary.json", R"({"scan_count": 2, "real_time_factor": 12.5,
        "per_scan_ms": {"median": 3.25}, "config": {"backend": "ieskf"}})");
    std::string pcd = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z" +
                      std::string(deviation ? " deviation_m intensity" : "") + "\nSIZE 4 4 4" +
                      (deviation ? " 4 4" : "") + "\nTYPE F F F" + (deviation ? " F F" : "") +
                      "\nCOUNT 1 1 1" + (deviation ? " 1 1" : "") + "\nWIDTH " +
                      std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                      std::to_string(points) + "\nDATA binary\n";
    for (size_t i = 0; i < points; ++i) {
      const float row[5] = {static_cast<float>(i), 1.0f, 2.0f + 0.5f * static_cast<float>(i),
                            static_cast<float>(i) * 0.001f, 3.0f * static_cast<float>(i)};
      pcd.append(reinterpret_cast<const char*>(row), (deviation ? 5 : 3) * sizeof(float));
    }
    Write(rel + "/map.pcd", pcd);
  }

  std::string dir_;
};

TEST(ReportArrayTest, IsBase64OfLittleEndianFloat32) {
  EXPECT_EQ(ReportArray({}), "");
  EXPECT_EQ(ReportArray({1.0f}), "AACAPw==");          // 00 00 80 3f
  EXPECT_EQ(ReportArray({1.0f, -2.0f}), "AACAPwAAAMA=");  // .. 00 00 00 c0
  const std::vector<float> values = {0.0f, 3.5f, -1e-7f, 12345.678f, 1e30f};
  EXPECT_EQ(DecodeArray(ReportArray(values)), values);
}

TEST(ThinningStrideTest, KeepsAtMostMaxPoints) {
  EXPECT_EQ(ThinningStride(10, 100), 1u);
  EXPECT_EQ(ThinningStride(100, 100), 1u);
  EXPECT_EQ(ThinningStride(1000, 100), 10u);
  EXPECT_EQ(ThinningStride(1001, 100), 11u);
  for (size_t n : {101u, 999u, 12345u, 2000000u}) {
    const size_t stride = ThinningStride(n, 100);
    EXPECT_LE((n + stride - 1) / stride, 100u) << n;       // points kept
    EXPECT_GT((n + stride - 2) / (stride - 1), 100u) << n;  // the next finer stride keeps too many
  }
}

TEST(MetricColumnsTest, NewNumericColumnsAppearWithoutNaming) {
  const std::vector<json> rows = {
      json{{"label", "a"}, {"ate_rmse_m", 0.1}, {"eval", {{"ape", 1}}}, {"status", "ok"}},
      json{{"label", "b"}, {"ate_rmse_m", 0.2}, {"map_rms_m", 0.03},
           {"map", {{"completeness", 0.9}, {"name", "x"}}}}};
  const std::vector<std::string> columns = MetricColumns(rows, {"label", "status"}, {"eval"});
  EXPECT_EQ(columns, (std::vector<std::string>{"label", "status", "ate_rmse_m", "map_rms_m",
                                               "map.completeness"}));
  EXPECT_EQ(ColumnValue(rows[1], "map.completeness"), 0.9);
  EXPECT_TRUE(ColumnValue(rows[0], "map_rms_m").is_null());
}

TEST_F(ReportDataTest, MissingOrEmptyFoldersAreInvalidInput) {
  for (const std::string& d : {Path("missing"), dir_}) {
    StatusOr<json> m = BuildReportModel(d, ReportOptions());
    ASSERT_FALSE(m.ok());
    EXPECT_EQ(m.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(m.status().message().find(d), std::string::npos) << m.status().message();
  }
  Write("bad/compare.json", "{ not json");
  StatusOr<json> m = BuildReportModel(Path("bad"), ReportOptions());
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("compare.json"), std::string::npos);
}

TEST_F(ReportDataTest, RunFolderWithDeviationIsThinnedAndColouredByDeviation) {
  WriteRun("run", Straight(0.0), 1000, true);
  ASSERT_TRUE(WriteTum(Path("gt.tum"), Straight(0.0)).ok());
  ReportOptions options;
  options.gt = Path("gt.tum");
  options.max_points = 300;
  StatusOr<json> m = BuildReportModel(Path("run"), options);
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_EQ((*m)["kind"], "run");
  const json& cloud = (*m)["cloud"];
  EXPECT_EQ(cloud["field"], "deviation_m");
  EXPECT_EQ(cloud["total"], 1000);
  EXPECT_EQ(cloud["stride"], 4);
  EXPECT_EQ(cloud["shown"], 250);
  const std::vector<float> xyz = DecodeArray(cloud["xyz"]), value = DecodeArray(cloud["value"]);
  ASSERT_EQ(xyz.size(), 750u);
  ASSERT_EQ(value.size(), 250u);
  for (size_t k = 0; k < value.size(); ++k) {
    EXPECT_EQ(xyz[3 * k], static_cast<float>(4 * k));                    // every 4th point
    EXPECT_FLOAT_EQ(value[k], static_cast<float>(4 * k) * 0.001f);  // its deviation_m
  }
  // The intensity is offered beside it, for the same points.
  ASSERT_TRUE(cloud["other_fields"].contains("intensity"));
  const std::vector<float> intensity = DecodeArray(cloud["other_fields"]["intensity"]);
  ASSERT_EQ(intensity.size(), 250u);
  for (size_t k = 0; k < intensity.size(); ++k) EXPECT_EQ(intensity[k], 12.0f * static_cast<float>(k));
  // The estimate equals the truth: aligned onto it, no along-axis error.
  const json& run = (*m)["runs"][0];
  EXPECT_TRUE(run["aligned"].get<bool>());
  const std::vector<float> err = DecodeArray(run["axis_error"]["err"]);
  ASSERT_EQ(err.size(), 101u);
  for (float e : err) EXPECT_NEAR(e, 0.0f, 1e-5f);
  EXPECT_EQ(DecodeArray(run["trajectory"]["t"]).back(), 10.0f);  // seconds from the first GT pose
  // scans.csv: the plotted columns present in the file, diverged as 0/1, empty as NaN.
  std::map<std::string, std::vector<float>> cols;
  std::vector<std::string> order;
  for (const json& c : run["scans"]["columns"]) {
    order.push_back(c["name"]);
    cols[c["name"]] = DecodeArray(c["values"]);
  }
  EXPECT_EQ(order, (std::vector<std::string>{"rv_active", "coplanar_fraction", "nis",
                                             "residual_rms_m", "diverged"}));
  EXPECT_EQ(cols["rv_active"], (std::vector<float>{0.0f, 1.0f}));
  EXPECT_EQ(cols["diverged"], (std::vector<float>{0.0f, 1.0f}));
  EXPECT_TRUE(std::isnan(cols["nis"][1]));
  // The table: the summary's numbers (nested one level), the eval metrics, no config.
  const json& table = (*m)["table"];
  const std::vector<std::string> columns = table["columns"];
  auto value_of = [&](const std::string& c) {
    for (size_t i = 0; i < columns.size(); ++i)
      if (columns[i] == c) return table["rows"][0][i];
    return json();
  };
  EXPECT_EQ(value_of("real_time_factor"), 12.5);
  EXPECT_EQ(value_of("per_scan_ms.median"), 3.25);
  EXPECT_NEAR(value_of("ate_rmse_m").get<double>(), 0.0, 1e-9);
  EXPECT_TRUE(value_of("config.backend").is_null());
}

TEST_F(ReportDataTest, RunWithoutDeviationIsColouredByHeightAndBadGtIsInvalidInput) {
  WriteRun("run", Straight(0.0), 10, false);
  StatusOr<json> m = BuildReportModel(Path("run"), ReportOptions());
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_EQ((*m)["cloud"]["field"], "z");
  EXPECT_TRUE((*m)["cloud"]["other_fields"].empty()) << "no intensity in the map: none offered";
  EXPECT_EQ(DecodeArray((*m)["cloud"]["value"])[3], 3.5f);  // z of point 3
  EXPECT_EQ((*m)["cloud"]["stride"], 1);
  EXPECT_TRUE((*m)["gt"].is_null());
  EXPECT_FALSE((*m)["runs"][0]["aligned"].get<bool>());
  ReportOptions options;
  options.gt = Path("nothing.tum");
  m = BuildReportModel(Path("run"), options);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("--gt"), std::string::npos) << m.status().message();
}

// A run in a national grid (UTM: a float32 steps by 0.5 m at a northing of
// 5.4e6 m): the page's float32 positions are relative to the ground truth's
// local origin, as fine as near zero, and a note gives that origin.
TEST_F(ReportDataTest, PositionsFarFromZeroAreDrawnRelativeToALocalOrigin) {
  const Eigen::Vector3d utm(500000.0, 5400000.0, 0.0);
  Trajectory truth = Straight(0.0);
  for (StampedPose& p : truth) p.p_world_imu += utm;
  WriteRun("run", truth, 0, false);
  std::vector<Eigen::Vector3d> map = {utm + Eigen::Vector3d(1.25, 0.5, 2.0)};
  ASSERT_TRUE(WriteMapPcd(Path("run/map.pcd"), map).ok());  // float64 x y z
  ASSERT_TRUE(WriteTum(Path("gt.tum"), truth).ok());
  ReportOptions options;
  options.gt = Path("gt.tum");
  StatusOr<json> m = BuildReportModel(Path("run"), options);
  ASSERT_TRUE(m.ok()) << m.status().message();
  const Trajectory local = Straight(0.0);
  for (const json* t : {&(*m)["gt"]["xyz"], &(*m)["runs"][0]["trajectory"]["xyz"]}) {
    const std::vector<float> xyz = DecodeArray(*t);
    ASSERT_EQ(xyz.size(), 3 * local.size());
    for (size_t k = 0; k < local.size(); ++k)
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(xyz[3 * k + a], local[k].p_world_imu[a], 1e-5) << k << " " << a;
  }
  EXPECT_EQ(DecodeArray((*m)["cloud"]["xyz"]), (std::vector<float>{1.25f, 0.5f, 2.0f}));
  const std::vector<std::string> notes = (*m)["notes"];
  EXPECT_NE(std::find(notes.begin(), notes.end(),
                      "positions are drawn relative to (500000.000, 5400000.000, 0.000) m"),
            notes.end());
}

// A run folder of `refine --control` in a UTM-sized frame: the residual table
// and the marks, drawn relative to the page's origin.
TEST_F(ReportDataTest, ControlPointsOfARefineAreTabledAndDrawnAsMarks) {
  const Eigen::Vector3d utm(500000.0, 5400000.0, 0.0);
  Trajectory est = Straight(0.0);
  for (StampedPose& p : est) p.p_world_imu += utm;
  WriteRun("run", est, 0, false);
  Write("run/control.csv",
        "name,role,kind,x,y,z,x_est,y_est,z_est,dx,dy,dz,d3d,sigma_m,t_s,scans\n"
        "M1,control,mark,500000.0000,5400000.0000,0.7000,500000.0030,5400000.0000,0.7000,"
        "0.0030,0.0000,0.0000,0.0030,0.005,1.000,0\n"
        "M2,check,mark,500010.0000,5400000.0000,0.7000,500010.0000,5400000.0120,0.7000,"
        "0.0000,0.0120,0.0000,0.0120,0.005,6.000,0\n");
  StatusOr<json> m = BuildReportModel(Path("run"), ReportOptions());
  ASSERT_TRUE(m.ok()) << m.status().message();
  const json& c = (*m)["control"];
  ASSERT_TRUE(c.is_object()) << m->dump();
  ASSERT_EQ(c["rows"].size(), 2u);
  EXPECT_EQ(c["rows"][1][0], "M2");
  EXPECT_EQ(c["rows"][1][1], "check");
  EXPECT_NEAR(c["rows"][1][6].get<double>(), 0.012, 1e-9);  // d3d_m
  EXPECT_EQ(DecodeArray(c["marks"]["xy"]), (std::vector<float>{0.0f, 0.0f, 10.0f, 0.0f}));
  // A control.csv that is not one: a note, no table.
  Write("run/control.csv", "name,x\nA,1\n");
  m = BuildReportModel(Path("run"), ReportOptions());
  ASSERT_TRUE(m.ok());
  EXPECT_TRUE((*m)["control"].is_null());
}

// A compare folder as `rvlio compare` writes it, run from another directory
// (paths in compare.json relative to that one), with a map column compare
// does not have today.
TEST_F(ReportDataTest, CompareFolderShowsEveryVariantAndAnyMetricColumn) {
  fs::create_directories(Path("cmp/data"));
  ASSERT_TRUE(WriteTum(Path("cmp/data/gt.tum"), Straight(0.0)).ok());
  WriteRun("cmp/ieskf_rv_on", Straight(0.02), 20, false);
  WriteRun("cmp/refine", Straight(0.0), 20, false);
  Write("cmp/compare.json", R"({"gt": "elsewhere/cmp/data/gt.tum", "variants": [
      {"variant": "ieskf_rv_on", "label": "IESKF, RV on", "status": "ok", "dir": "elsewhere/cmp/ieskf_rv_on",
       "ate_rmse_m": 0.0123456789, "map_rms_m": 0.031, "eval": {"ape": {"rmse": 0.0123456789}}},
      {"variant": "smoother_rv_off", "label": "smoother", "status": "failed", "exit_code": 1,
       "dir": "elsewhere/cmp/smoother_rv_off"},
      {"variant": "refine", "label": "refine", "status": "ok", "dir": "elsewhere/cmp/refine",
       "ate_rmse_m": 0.01, "map_rms_m": 0.02}]})");
  StatusOr<json> m = BuildReportModel(Path("cmp"), ReportOptions());
  ASSERT_TRUE(m.ok()) << m.status().message();
  EXPECT_EQ((*m)["kind"], "demo");  // a data/ folder next to compare.json
  EXPECT_EQ((*m)["gt"]["file"], Path("cmp/data/gt.tum"));  // re-rooted at the folder
  ASSERT_EQ((*m)["runs"].size(), 2u);                       // the failed one has no outputs
  EXPECT_EQ((*m)["cloud"]["run"], "refine");
  const json& table = (*m)["table"];
  const std::vector<std::string> columns = table["columns"];
  EXPECT_EQ(std::vector<std::string>(columns.begin(), columns.begin() + 3),
            (std::vector<std::string>{"label", "status", "ate_rmse_m"}));
  const size_t map_rms = std::find(columns.begin(), columns.end(), "map_rms_m") - columns.begin();
  ASSERT_LT(map_rms, columns.size());
  EXPECT_NE(std::find(columns.begin(), columns.end(), "exit_code"), columns.end());
  EXPECT_EQ(std::find(columns.begin(), columns.end(), "eval.ape"), columns.end());
  EXPECT_EQ(table["rows"][0][2], 0.0123456789);
  EXPECT_EQ(table["rows"][0][map_rms], 0.031);
  EXPECT_EQ(table["rows"][2][map_rms], 0.02);
  EXPECT_TRUE(table["rows"][1][2].is_null());
}

TEST_F(ReportDataTest, PageInlinesEverythingAndEscapesTheData) {
  WriteRun("run", Straight(0.0), 5, false);
  StatusOr<json> m = BuildReportModel(Path("run"), ReportOptions());
  ASSERT_TRUE(m.ok()) << m.status().message();
  (*m)["title"] = "a </script><b> title";
  const std::string page = RenderReportHtml({FolderKind::kRun, (*m)["title"], JsonText(*m, -1)});
  EXPECT_EQ(page.find("@RVLIO_"), std::string::npos);        // every marker filled
  EXPECT_NE(page.find("REVISION"), std::string::npos);       // three.js is inlined
  EXPECT_NE(page.find("RvlioReport"), std::string::npos);    // and the page's script
  EXPECT_EQ(page.find("</script><b>"), std::string::npos);   // the data cannot end its element
  EXPECT_NE(page.find("a &lt;/script&gt;&lt;b&gt; title"), std::string::npos);  // <title>
  for (const char* fetch : {"src=\"http", "href=\"http", "src=\"//", "href=\"//"})
    EXPECT_EQ(page.find(fetch), std::string::npos) << fetch;  // nothing from the network
  // The data element parses back to the model.
  const std::string open = "<script id=\"rvlio-data\" type=\"application/json\">";
  const size_t begin = page.find(open) + open.size();
  const json back = json::parse(page.substr(begin, page.find("</script>", begin) - begin));
  EXPECT_EQ(back, *m);

  StatusOr<WrittenReport> w = WriteReport(Path("run"), "", ReportOptions());
  ASSERT_TRUE(w.ok()) << w.status().message();
  EXPECT_EQ(w->path, Path("run") + "/report.html");
  EXPECT_EQ(fs::file_size(w->path), w->bytes);
}

}  // namespace
}  // namespace rvlio::experiments::report
