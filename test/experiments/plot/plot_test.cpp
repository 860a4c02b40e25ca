// End to end: scripts/rvlio_plot.py on generated run directories. Checks the
// figures it prints (matched poses, along-axis error under each alignment),
// that PNG (150 dpi) and PDF files are written atomically, and that bad input
// gives one error line, exit 2 and no output. Skipped when the script finds no
// matplotlib (`rvlio_plot.py check` fails).
#include <stdlib.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rvlio/outputs/run_outputs.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

const std::string kScript = std::string(RVLIO_SOURCE_DIR) + "/scripts/rvlio_plot.py";
constexpr double kT0 = 1700000000.0;  // absolute stamps, as in real bags [s]
constexpr double kGtPeriod = 0.01;    // 100 Hz ground truth [s]
constexpr double kStampOffset = 0.004;  // estimate stamp - its GT stamp [s], < 0.01
const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

struct Pose {
  double t = 0.0;  // s
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
};

struct Result {
  int exit_code = -1;
  std::string out, err;
};

struct RunFigures {
  int matched = -1, total = -1;
  double max_error = NAN, final_error = NAN;  // m
};

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

std::string TumText(const std::vector<Pose>& poses) {
  std::ostringstream os;
  os << "# t x y z qx qy qz qw\n";
  char line[256];
  for (const Pose& p : poses) {
    std::snprintf(line, sizeof(line), "%.9f %.9f %.9f %.9f %.12f %.12f %.12f %.12f\n", p.t,
                  p.p.x(), p.p.y(), p.p.z(), p.q.x(), p.q.y(), p.q.z(), p.q.w());
    os << line;
  }
  return os.str();
}

Eigen::Quaterniond Yaw(double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
}

// 20 s at 100 Hz along direction `yaw` in the x-y plane, accelerating,
// optionally with a lateral and vertical wiggle (then not a straight line).
std::vector<Pose> GroundTruth(double yaw, bool wiggle) {
  const Eigen::Vector3d d(std::cos(yaw), std::sin(yaw), 0.0), n(-d.y(), d.x(), 0.0);
  std::vector<Pose> gt;
  for (int k = 0; k <= 2000; ++k) {
    const double s = k * kGtPeriod;
    Pose p;
    p.t = kT0 + s;
    p.p = Eigen::Vector3d(1.0, 2.0, 1.5) + (0.5 * s + 0.02 * s * s) * d;
    if (wiggle) p.p += 0.3 * std::sin(0.5 * s) * n + 0.2 * std::cos(0.3 * s) * Eigen::Vector3d::UnitZ();
    p.q = Yaw(yaw);
    gt.push_back(p);
  }
  return gt;
}

// An estimate at 10 Hz, stamped kStampOffset after GT samples 5, 15, 25, ...:
// the GT pose plus an along-axis drift c (t - t_first)^2, expressed in another
// frame (p_est = R p + t), plus one pose 0.5 s after the GT ends (unmatched).
std::vector<Pose> Estimate(const std::vector<Pose>& gt, const Eigen::Vector3d& axis, double c,
                           const Eigen::Quaterniond& R, const Eigen::Vector3d& t) {
  std::vector<Pose> est;
  const double t_first = gt[5].t;
  for (size_t k = 5; k < gt.size(); k += 10) {
    Pose p;
    p.t = gt[k].t + kStampOffset;
    const double dt = gt[k].t - t_first;
    p.p = R * (gt[k].p + c * dt * dt * axis) + t;
    p.q = R * gt[k].q;
    est.push_back(p);
  }
  Pose late = est.back();
  late.t = gt.back().t + 0.5;
  est.push_back(late);
  return est;
}

// Expected along-axis error of Estimate() at its last matched pose.
double ExpectedFinalError(const std::vector<Pose>& gt, double c) {
  size_t last = 5;
  while (last + 10 < gt.size()) last += 10;
  const double dt = gt[last].t - gt[5].t;
  return c * dt * dt;
}

// scans.csv of `est` (one row per pose) with RV active from the 40th scan.
std::string ScansCsv(const std::vector<Pose>& est, bool with_acc, bool coarse_t) {
  std::ostringstream os;
  os << "t,status,raw_points,points,constraints,iterations,rv_active,n_alpha_x,n_alpha_y,"
        "n_alpha_z,scv,coplanar,repaired,K,rv_iterations,coplanar_fraction,localizability,ms,"
        "x,y,z"
     << (with_acc ? ",acc_x,acc_y,acc_z\n" : "\n");
  for (size_t i = 0; i < est.size(); ++i) {
    const bool weak = i >= 40;
    char t[64];
    std::snprintf(t, sizeof(t), coarse_t ? "%.9g" : "%.9f", est[i].t);
    os << t << ",updated,60000,4000," << (weak ? 700 : 1500) << ",3," << (weak ? 1 : 0)
       << ",0,1,0," << (weak ? 3 : 40) << ',' << (weak ? 697 : 1460) << ',' << (weak ? 12 : 0)
       << ",1.5,2," << (weak ? 0.96 : 0.6) << ',' << (weak ? 0.05 : 300.0) << ",12.5,"
       << est[i].p.x() << ',' << est[i].p.y() << ',' << est[i].p.z();
    if (with_acc) os << ',' << (i == 100 ? 3.0 : 0.05) << ",0.0,9.81";
    os << '\n';
  }
  return os.str();
}

// PNG signature, then chunks up to IDAT: IHDR size and pHYs density.
struct PngInfo {
  bool signature = false;
  uint32_t width = 0, height = 0, ppm_x = 0, ppm_y = 0;
};

uint32_t BigEndian(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(s[at + i]);
  return v;
}

PngInfo ReadPngInfo(const std::string& bytes) {
  PngInfo info;
  info.signature = bytes.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0;
  for (size_t at = 8; info.signature && at + 12 <= bytes.size();) {
    const uint32_t n = BigEndian(bytes, at);
    const std::string type = bytes.substr(at + 4, 4);
    if (type == "IHDR" && n >= 8) {
      info.width = BigEndian(bytes, at + 8);
      info.height = BigEndian(bytes, at + 12);
    } else if (type == "pHYs" && n == 9) {
      info.ppm_x = BigEndian(bytes, at + 8);
      info.ppm_y = BigEndian(bytes, at + 12);
    } else if (type == "IDAT") {
      break;
    }
    at += 12 + n;
  }
  return info;
}

class PlotScriptTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string cmd = "python3 '" + kScript + "' check >/dev/null 2>&1";
    const int status = std::system(cmd.c_str());
    available_ = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  }

  void SetUp() override {
    if (!available_) GTEST_SKIP() << "rvlio_plot.py check failed: no matplotlib";
    std::string tmpl = ::testing::TempDir() + "rvlio_plot_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
    fs::create_directories(dir_ + "/out");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  Result Plot(const std::string& args) {
    const std::string out = dir_ + "/stdout", err = dir_ + "/stderr";
    const std::string cmd = "python3 '" + kScript + "' " + args + " >" + out + " 2>" + err;
    const int status = std::system(cmd.c_str());
    Result r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = ReadAll(out);
    r.err = ReadAll(err);
    return r;
  }

  // A run directory DIR/name with trajectory.tum, scans.csv and summary.json.
  std::string MakeRun(const std::string& name, const std::vector<Pose>& est, bool with_acc = true,
                      bool coarse_t = false) {
    const std::string run = dir_ + "/" + name;
    fs::create_directories(run);
    WriteText(run + "/trajectory.tum", TumText(est));
    WriteText(run + "/scans.csv", ScansCsv(est, with_acc, coarse_t));
    WriteText(run + "/summary.json",
              "{\"backend\": \"ieskf\", \"config\": {\"rv\": {\"enabled\": true}}, "
              "\"per_scan_ms\": {\"median\": 12.5}, \"real_time_factor\": 4.2}\n");
    return run;
  }

  std::string WriteGt(const std::vector<Pose>& gt) {
    const std::string path = dir_ + "/gt.tum";
    WriteText(path, TumText(gt));
    return path;
  }

  // Exactly PREFIX_kind.png and .pdf in out/ (no temp files), both valid.
  void ExpectFigures(const std::string& kind) {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_ + "/out"))
      names.insert(entry.path().filename().string());
    const std::string png = "fig_" + kind + ".png", pdf = "fig_" + kind + ".pdf";
    EXPECT_EQ(names, (std::set<std::string>{png, pdf}));
    const PngInfo info = ReadPngInfo(ReadAll(dir_ + "/out/" + png));
    EXPECT_TRUE(info.signature) << png;
    EXPECT_GE(info.width, 900u) << png;
    EXPECT_GE(info.height, 500u) << png;
    EXPECT_EQ(info.ppm_x, 5906u) << png << ": not 150 dpi";  // 150 / 0.0254 m
    EXPECT_EQ(info.ppm_y, 5906u) << png;
    const std::string pdf_bytes = ReadAll(dir_ + "/out/" + pdf);
    EXPECT_EQ(pdf_bytes.rfind("%PDF-", 0), 0u) << pdf;
    EXPECT_NE(pdf_bytes.find("%%EOF", pdf_bytes.size() > 32 ? pdf_bytes.size() - 32 : 0),
              std::string::npos)
        << pdf << " is truncated";
  }

  // Exit 2, one stderr line "rvlio_plot: error: ..." containing `part`, no output.
  void ExpectBadInput(const std::string& args, const std::string& part) {
    const Result r = Plot(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("rvlio_plot: error: ", 0), 0u) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "more than one line: " << r.err;
    EXPECT_NE(r.err.find(part), std::string::npos) << "'" << part << "' not in: " << r.err;
    EXPECT_TRUE(fs::is_empty(dir_ + "/out")) << args << " left output behind";
  }

  std::string Out() const { return "--out " + dir_ + "/out/fig"; }

  static bool available_;
  std::string dir_;
};

bool PlotScriptTest::available_ = false;

// The script's line "run 'LABEL': M/N poses matched, along-axis error max X m,
// final Y m". Parsed with sscanf, not <regex>: gcc 12's std::regex trips
// -Wmaybe-uninitialized inside libstdc++ at -O1 (the sanitizer build), which
// RVLIO_WERROR turns into an error.
RunFigures ParseRun(const std::string& out, const std::string& label) {
  RunFigures f;
  const std::string prefix = "run '" + label + "': ";
  const size_t at = out.find(prefix);
  if (at == std::string::npos) return f;
  int matched = 0, total = 0;
  double max_error = 0.0, final_error = 0.0;
  if (std::sscanf(out.c_str() + at + prefix.size(),
                  "%d/%d poses matched, along-axis error max %lf m, final %lf m", &matched,
                  &total, &max_error, &final_error) == 4) {
    f.matched = matched;
    f.total = total;
    f.max_error = max_error;
    f.final_error = final_error;
  }
  return f;
}

Eigen::Quaterniond RandomRotation(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(*rng), n(*rng), n(*rng), n(*rng)).normalized();
}

// Origin alignment undoes an arbitrary frame change (it is exact at the first
// pose), so the printed along-axis error is the injected drift, for random
// tunnel directions, frames and drift rates; the late pose stays unmatched.
TEST_F(PlotScriptTest, OriginAlignmentRecoversTheInjectedAlongAxisDrift) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), rate(-0.01, 0.01);
  std::normal_distribution<double> offset(0.0, 20.0);
  const double yaw = angle(rng);
  const std::vector<Pose> gt = GroundTruth(yaw, false);
  const Eigen::Vector3d axis(std::cos(yaw), std::sin(yaw), 0.0);
  std::string args = "trajectories --gt " + WriteGt(gt) + " " + Out();
  std::vector<double> rates;
  for (int i = 0; i < 4; ++i) {
    rates.push_back(rate(rng));
    const Eigen::Vector3d t(offset(rng), offset(rng), offset(rng));
    args += " --run r" + std::to_string(i) + "=" +
            MakeRun("r" + std::to_string(i), Estimate(gt, axis, rates[i], RandomRotation(&rng), t));
  }
  const Result r = Plot(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int i = 0; i < 4; ++i) {
    const RunFigures f = ParseRun(r.out, "r" + std::to_string(i));
    const double expected = ExpectedFinalError(gt, rates[i]);
    EXPECT_EQ(f.matched, 200) << r.out;
    EXPECT_EQ(f.total, 201) << r.out;
    EXPECT_NEAR(f.final_error, expected, 2e-6) << "run " << i;
    EXPECT_NEAR(f.max_error, std::abs(expected), 2e-6) << "run " << i;
  }
  ExpectFigures("trajectories");
}

// SE(3) (Umeyama) alignment removes a rigid transformation of a non-straight
// trajectory entirely; with --align none the same runs are metres off.
TEST_F(PlotScriptTest, Se3AlignmentRemovesARigidTransformation) {
  std::mt19937 rng(11);
  const std::vector<Pose> gt = GroundTruth(0.4, true);
  const Eigen::Vector3d axis(std::cos(0.4), std::sin(0.4), 0.0);
  std::string runs;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d t(5.0 + i, -3.0, 2.0);
    runs += " --run s" + std::to_string(i) + "=" +
            MakeRun("s" + std::to_string(i), Estimate(gt, axis, 0.0, RandomRotation(&rng), t));
  }
  const std::string gt_path = WriteGt(gt);
  Result r = Plot("trajectories --no-z --align se3 --gt " + gt_path + runs + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int i = 0; i < 3; ++i)
    EXPECT_LT(ParseRun(r.out, "s" + std::to_string(i)).max_error, 2e-6) << r.out;
  ExpectFigures("trajectories");
  r = Plot("trajectories --align none --gt " + gt_path + runs + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int i = 0; i < 3; ++i)
    EXPECT_GT(ParseRun(r.out, "s" + std::to_string(i)).max_error, 1.0) << r.out;
}

// rv-profile with every column and --gt: the run's own error line, no notes.
TEST_F(PlotScriptTest, RvProfileWithGroundTruth) {
  const std::vector<Pose> gt = GroundTruth(1.0, false);
  const Eigen::Vector3d axis(std::cos(1.0), std::sin(1.0), 0.0);
  const std::string run =
      MakeRun("rv_on", Estimate(gt, axis, 0.002, Eigen::Quaterniond::Identity(), kZero));
  const Result r = Plot("rv-profile --run " + run + " --gt " + WriteGt(gt) + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(ParseRun(r.out, "rv_on").final_error, ExpectedFinalError(gt, 0.002), 2e-6)
      << r.out;
  EXPECT_EQ(r.out.find("note:"), std::string::npos) << r.out;
  // The GT moves 0.5 s + 0.02 s^2 along its axis: 0.04 m/s^2 throughout.
  const std::string key = "acceleration along the axis median ";
  const size_t at = r.out.find(key);
  ASSERT_NE(at, std::string::npos) << r.out;
  EXPECT_NEAR(std::stod(r.out.substr(at + key.size())), 0.04, 1e-4) << r.out;
  ExpectFigures("rv_profile");
}

// An older scans.csv (no acc_* columns, stamps printed with 9 significant
// digits) still plots: the acceleration panel is left out and the stamps come
// from trajectory.tum, both said on stdout.
TEST_F(PlotScriptTest, RvProfileOfAnOlderScansFile) {
  const std::vector<Pose> gt = GroundTruth(0.0, false);
  const std::string run = MakeRun(
      "old", Estimate(gt, Eigen::Vector3d::UnitX(), 0.0, Eigen::Quaterniond::Identity(), kZero),
      /*with_acc=*/false, /*coarse_t=*/true);
  const Result r = Plot("rv-profile --run " + run + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("no column acc_x"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("using the stamps of trajectory.tum"), std::string::npos) << r.out;
  ExpectFigures("rv_profile");
}

// Ablation over seeds (one cell without any value), two metrics.
TEST_F(PlotScriptTest, AblationBarChartOverSeeds) {
  std::ostringstream csv;
  csv << "sequence,variant,seed,ate_rmse,ms_median\n";
  for (const char* seq : {"tunnel", "corridor"})
    for (const char* variant : {"rv_off", "rv_on", "smoother"})
      for (int seed = 1; seed <= 3; ++seed) {
        const bool crashed = std::string(seq) == "corridor" && std::string(variant) == "smoother";
        csv << seq << ',' << variant << ',' << seed << ','
            << (crashed ? "" : std::to_string(0.1 * seed)) << ',' << 10 + seed << '\n';
      }
  WriteText(dir_ + "/ablation.csv", csv.str());
  const Result r = Plot("ablation --table " + dir_ + "/ablation.csv --metric ate_rmse "
                        "--metric ms_median " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectFigures("ablation");
}

// A summary table with <metric>_mean/_std columns and no seed column.
TEST_F(PlotScriptTest, AblationFromMeanAndStdColumns) {
  WriteText(dir_ + "/summary.csv",
            "sequence,variant,ate_rmse_mean,ate_rmse_std\n"
            "tunnel,rv_off,2.5,0.4\ntunnel,rv_on,0.1,0.02\n");
  const Result r = Plot("ablation --table " + dir_ + "/summary.csv " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectFigures("ablation");
}

// The compare.csv of `rvlio compare`: one bar per variant and metric, a failed
// variant (empty metrics) drawn as "failed"; the values printed are the table's.
TEST_F(PlotScriptTest, CompareBarsFromACompareTable) {
  WriteText(dir_ + "/compare.csv",
            "variant,label,status,exit_code,init,scans,ate_rmse_m,rpe_rmse_m,axis_max_m\n"
            "ieskf_rv_off,\"IESKF, RV off\",ok,0,,90,0.0102,0.0022,0.0263\n"
            "smoother_rv_on,\"smoother, RV on\",failed,2,,0,,,\n"
            "refine,\"refine (from IESKF, RV off)\",ok,0,ieskf_rv_off,90,0.0027,0.00035,0.0052\n");
  const Result r = Plot("compare-bars --table " + dir_ + "/compare.csv " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("variant ieskf_rv_off: ate_rmse_m 0.0102, rpe_rmse_m 0.0022, "
                       "axis_max_m 0.0263"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("variant smoother_rv_on: ate_rmse_m nan"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("variant refine: ate_rmse_m 0.0027"), std::string::npos) << r.out;
  ExpectFigures("compare_bars");
}

// deviation.csv of `rvlio run --map`: the peak printed is the table's
// largest p95 |deviation| at its chainage; a table without the columns is
// refused.
TEST_F(PlotScriptTest, DeviationAlongTheChainage) {
  const std::string run = dir_ + "/survey";
  fs::create_directories(run);
  WriteText(run + "/deviation.csv",
            "chainage_m,count,median_m,median_abs_m,p95_abs_m,max_abs_m\n"
            "0,100,0.001,0.002,0.01,0.02\n1,120,0.02,0.021,0.048,0.06\n"
            "2,90,,,,\n3,110,-0.001,0.003,0.012,0.03\n");
  const Result r = Plot("deviation --run " + run + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("peak p95 |deviation| 0.0480 m at chainage 1.0 m"), std::string::npos)
      << r.out;
  ExpectFigures("deviation");
  for (const auto& entry : fs::directory_iterator(dir_ + "/out")) fs::remove(entry.path());
  // With the per-surface columns: a second panel, and each surface's
  // largest signed median (the left wall's convergence at 1 m).
  std::string sides = "chainage_m,count,median_m,median_abs_m,p95_abs_m,max_abs_m";
  for (const char* side : {"left", "right", "floor", "ceiling"})
    sides += std::string(",") + side + "_count," + side + "_median_m," + side + "_p95_abs_m";
  WriteText(run + "/deviation.csv",
            sides + "\n0,100,0.001,0.002,0.01,0.02,25,0.002,0.01,25,0.001,0.01,25,0,0.01,25,-0.001,0.01\n"
                    "1,120,0.02,0.021,0.048,0.06,30,0.045,0.05,30,0.002,0.01,30,0.001,0.01,30,0,0.01\n"
                    "2,0,,,,,0,,,0,,,0,,,0,,\n");
  const Result with_sides = Plot("deviation --run " + run + " " + Out());
  ASSERT_EQ(with_sides.exit_code, 0) << with_sides.err;
  EXPECT_NE(with_sides.out.find("left 0.0450 m at 1.0 m, right 0.0020 m at 1.0 m"),
            std::string::npos)
      << with_sides.out;
  ExpectFigures("deviation");
  for (const auto& entry : fs::directory_iterator(dir_ + "/out")) fs::remove(entry.path());
  WriteText(run + "/deviation.csv", "chainage_m,count\n0,1\n");
  ExpectBadInput("deviation --run " + run + " " + Out(), "missing column(s) median_m");
}

// map.pcd coloured by its intensity (the picture of docs/outputs.md): the
// range printed is the field's 2nd to 98th percentile; a field the map does
// not have is refused naming the fields it has.
TEST_F(PlotScriptTest, MapColouredByIntensity) {
  const std::string run = dir_ + "/mapped";
  fs::create_directories(run);
  MapCloud map;
  map.has_intensity = map.has_time = map.has_ring = map.has_scan_index = true;
  for (int i = 0; i < 1000; ++i) {
    map.p.emplace_back(0.05 * i, (i % 2 == 0 ? 5.0 : -5.0) + 0.001 * (i % 7), 0.007 * i);
    map.intensity.push_back(static_cast<float>(i % 101));
    map.t_ns.push_back(1'700'000'000'000'000'000 + 1'000'000LL * i);
    map.ring.push_back(static_cast<uint16_t>(i % 32));
    map.scan_index.push_back(static_cast<uint32_t>(i / 100));
  }
  ASSERT_TRUE(WriteMapPcd(run + "/map.pcd", map, nullptr).ok());
  const Result r = Plot("map --run " + run + " " + Out());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1000 points, intensity 1.98 to 98"), std::string::npos) << r.out;
  ExpectFigures("map_intensity");
  for (const auto& entry : fs::directory_iterator(dir_ + "/out")) fs::remove(entry.path());
  ExpectBadInput("map --run " + run + " --field deviation_m " + Out(),
                 "has no field deviation_m (fields: x y z intensity time ring scan_index)");
}

// An --out ending in '/' is a folder: FOLDER/<kind>.png and .pdf.
TEST_F(PlotScriptTest, OutputPrefixEndingInSlashIsAFolder) {
  WriteText(dir_ + "/compare.csv", "variant,status,ate_rmse_m,rpe_rmse_m,axis_max_m\n"
                                   "a,ok,0.1,0.01,0.2\nb,ok,0.2,0.02,0.3\n");
  const Result r = Plot("compare-bars --table " + dir_ + "/compare.csv --out " + dir_ +
                        "/out/plots/");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir_ + "/out/plots"))
    names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"compare_bars.png", "compare_bars.pdf"}));
  EXPECT_TRUE(ReadPngInfo(ReadAll(dir_ + "/out/plots/compare_bars.png")).signature);
}

TEST_F(PlotScriptTest, BadInputIsOneErrorLineAndNoOutput) {
  const std::vector<Pose> gt = GroundTruth(0.0, false);
  const std::string gt_path = WriteGt(gt);
  const std::string run = MakeRun(
      "ok", Estimate(gt, Eigen::Vector3d::UnitX(), 0.0, Eigen::Quaterniond::Identity(), kZero));
  ExpectBadInput("trajectories --gt " + dir_ + "/none.tum --run a=" + run + " " + Out(),
                 "none.tum");
  ExpectBadInput("trajectories --gt " + gt_path + " --run a=" + dir_ + "/nothing " + Out(),
                 "nothing");

  std::vector<Pose> late = gt;  // every stamp after the GT has ended
  for (Pose& p : late) p.t += 0.5 + 20.0;
  ExpectBadInput("trajectories --gt " + gt_path + " --run late=" + MakeRun("late", late) + " " +
                     Out(),
                 "no estimate stamp");

  WriteText(dir_ + "/bad.tum", "# comment\n1700000000.0 1 2 3\n");
  ExpectBadInput("trajectories --gt " + dir_ + "/bad.tum --run a=" + run + " " + Out(),
                 "bad.tum:2");

  const std::string cut = dir_ + "/cut";
  fs::create_directories(cut);
  WriteText(cut + "/scans.csv", "t,status,raw_points,points,constraints\n1.0,updated,1,1,1\n");
  ExpectBadInput("rv-profile --run " + cut + " " + Out(), "missing column(s) rv_active, scv");

  WriteText(dir_ + "/abl.csv", "sequence,variant,ate_rmse\ntunnel,rv_on,0.1\n");
  ExpectBadInput("ablation --table " + dir_ + "/abl.csv --metric rpe " + Out(), "no column 'rpe'");
  ExpectBadInput("ablation --table " + dir_ + "/missing.csv " + Out(), "missing.csv");
  ExpectBadInput("compare-bars --table " + dir_ + "/abl.csv " + Out(),
                 "missing column(s) ate_rmse_m, rpe_rmse_m, axis_max_m");
  ExpectBadInput("trajectories --gt " + gt_path + " --align sim3 --run a=" + run + " " + Out(),
                 "--align");
}

}  // namespace
}  // namespace rvlio
