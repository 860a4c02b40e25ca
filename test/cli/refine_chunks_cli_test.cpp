// End to end: `rvlio refine --chunk K --of N` on a simulated tunnel, then
// `rvlio merge`: the merged trajectory agrees with the whole-sequence refine,
// is more accurate than the initial trajectory, has no step at the chunk
// borders, and bad chunk parameters, missing or foreign chunks and a partial
// initial trajectory are reported as the docs say (docs/refine.md).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "cli_util.h"

namespace rvlio {
namespace {

using testing_cli::EvalJson;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

// Two rounds and a 3 s overlap keep the suite short: three chunks of a 14 s
// tunnel (cores of ~4.3 s).
const char* const kFast = " --set refine.rounds=2 --set refine.job_overlap_s=3";

class RefineChunksCliTest : public testing_cli::IeskfTunnelSuite {
 protected:
  // The whole refine and chunks 1..3 of 3, which the merge checks work on.
  // Not in SetUpTestSuite: ctest runs each test case in its own process.
  static void RefineWholeAndChunks() {
    const ToolRun whole = RunTool(Refine("--out " + dir_ + "/whole"), dir_);
    ASSERT_EQ(whole.exit_code, 0) << whole.err;
    for (int k = 1; k <= 3; ++k) {
      const ToolRun chunk = RunTool(Refine(ChunkArgs(k, 3)), dir_);
      ASSERT_EQ(chunk.exit_code, 0) << chunk.err;
    }
  }
  static void CheckMergeAgreesWithWhole();
  static void CheckChunkJson();
  static void CheckBadMerges();

  static std::string ChunkDir(int k) { return dir_ + "/chunk" + std::to_string(k); }
  static std::string ChunkArgs(int k, int n) {
    return "--chunk " + std::to_string(k) + " --of " + std::to_string(n) + " --out " + ChunkDir(k);
  }
  // `rvlio refine` on the suite's bag from the IESKF run, fast settings.
  static std::string Refine(const std::string& extra, const std::string& init = "") {
    return "refine --bag " + Bag() + " --init " + (init.empty() ? Init() : init) + " --config " +
           Sensors() + kFast + " " + extra;
  }
  static std::string MergeArgs(const std::vector<int>& chunks, const std::string& out) {
    std::string args = "merge --out " + out;
    for (int k : chunks) args += " --chunks " + ChunkDir(k);
    return args;
  }
  static double Ate(const std::string& est) {
    const auto j = EvalJson(Truth(), est, dir_);
    return j.is_object() ? j["ape"]["rmse"].get<double>() : 1e9;
  }
};

struct Tum {
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> p;
};

Tum ReadPositions(const std::string& path) {
  Tum out;
  std::istringstream in(ReadFile(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream f(line);
    double t, x, y, z;
    f >> t >> x >> y >> z;
    out.t_s.push_back(t);
    out.p.emplace_back(x, y, z);
  }
  return out;
}

void RefineChunksCliTest::CheckMergeAgreesWithWhole() {
  const std::string out = dir_ + "/merged";
  const ToolRun merge = RunTool(MergeArgs({3, 1, 2}, out), dir_);  // any order
  ASSERT_EQ(merge.exit_code, 0) << merge.err;
  const auto summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_EQ(summary["command"], "merge");
  ASSERT_EQ(summary["chunks"].size(), 3u);
  for (int k = 1; k < 3; ++k) {
    EXPECT_GE(summary["chunks"][k]["shared_poses"].get<int>(), 25);  // 3 s at 10 Hz
    EXPECT_LT(summary["chunks"][k]["residual_rms_m"].get<double>(), 0.01);
  }
  const Tum merged = ReadPositions(out + "/trajectory.tum");
  const Tum whole = ReadPositions(dir_ + "/whole/trajectory.tum");
  ASSERT_EQ(merged.t_s, whole.t_s);  // the same scans, each once
  EXPECT_EQ(summary["scan_count"].get<size_t>(), whole.t_s.size());
  EXPECT_GT(summary["map_points"].get<int>(), 10000);

  // The merged frame is chunk 1's, which like the whole refine holds the
  // first pose at the initial trajectory's: compare positions directly.
  double sum_sq = 0.0;
  for (size_t i = 0; i < whole.p.size(); ++i) sum_sq += (merged.p[i] - whole.p[i]).squaredNorm();
  const double rms_m = std::sqrt(sum_sq / static_cast<double>(whole.p.size()));
  const double ate_init = Ate(Init()), ate_whole = Ate(dir_ + "/whole/trajectory.tum"),
               ate_merged = Ate(out + "/trajectory.tum");
  std::printf("ATE init %.4f whole %.4f merged %.4f m; merged - whole RMS %.4f m\n", ate_init,
              ate_whole, ate_merged, rms_m);
  // Measured (docs/refine.md, "Accuracy of chunk jobs"): init 15.0 mm, whole 6.2 mm, merged 6.4 mm, RMS 3.8 mm.
  EXPECT_LT(rms_m, 0.01);
  EXPECT_LT(ate_merged, ate_whole + 0.005);
  EXPECT_LT(ate_merged, 0.8 * ate_init);

  // No step at a border. The flight itself accelerates (its positions' second
  // differences reach ~4 cm), so the steps are those of the difference to
  // the whole refine, e_i = merged_i - whole_i: a jump at a border would be
  // one large |e_i - e_(i-1)|. Inside the shared intervals the step stays
  // within twice its largest value elsewhere (slowly varying drift
  // differences), or 1 mm.
  std::vector<double> borders_s;
  for (int k = 1; k < 3; ++k)
    borders_s.push_back(
        nlohmann::json::parse(ReadFile(ChunkDir(k) + "/chunk.json"))["core_end_ns"].get<int64_t>() * 1e-9);
  double at_borders_m = 0.0, elsewhere_m = 0.0;
  for (size_t i = 1; i < merged.p.size(); ++i) {
    const double step =
        ((merged.p[i] - whole.p[i]) - (merged.p[i - 1] - whole.p[i - 1])).norm();
    const bool shared = std::any_of(borders_s.begin(), borders_s.end(),
                                    [&](double b) { return std::abs(merged.t_s[i] - b) <= 1.5; });
    double& worst = shared ? at_borders_m : elsewhere_m;
    worst = std::max(worst, step);
  }
  std::printf("largest step of merged - whole: %.5f m at the borders, %.5f m elsewhere\n",
              at_borders_m, elsewhere_m);
  EXPECT_LT(at_borders_m, std::max(2.0 * elsewhere_m, 0.001));
}

void RefineChunksCliTest::CheckChunkJson() {
  const auto c1 = nlohmann::json::parse(ReadFile(ChunkDir(1) + "/chunk.json"));
  const auto c2 = nlohmann::json::parse(ReadFile(ChunkDir(2) + "/chunk.json"));
  EXPECT_EQ(c2["chunk"], 2);
  EXPECT_EQ(c2["of"], 3);
  EXPECT_EQ(c2["overlap_s"].get<double>(), 3.0);
  EXPECT_EQ(c1["options_hash"], c2["options_hash"]);
  EXPECT_EQ(c1["init_hash"], c2["init_hash"]);
  EXPECT_EQ(c1["core_end_ns"], c2["core_begin_ns"]);
  EXPECT_NEAR((c1["end_ns"].get<int64_t>() - c2["begin_ns"].get<int64_t>()) * 1e-9, 3.0, 1e-6);
  EXPECT_LT(c2["recording_scan_first"].get<int>(), c1["recording_scan_last"].get<int>());
  EXPECT_GE(c2["scans_refined"].get<int>(), 60);
  const auto summary = nlohmann::json::parse(ReadFile(ChunkDir(2) + "/summary.json"));
  EXPECT_EQ(summary["chunk"]["chunk"], 2);
  EXPECT_TRUE(summary["init_coverage"]["complete"].get<bool>());
}

// One case for the chunked refine and everything that needs its chunks.
TEST_F(RefineChunksCliTest, MergedChunksAgreeWithTheWholeRefineHaveNoBorderStepsAndRefuseBadSets) {
  RefineWholeAndChunks();
  if (HasFatalFailure()) return;
  CheckMergeAgreesWithWhole();
  CheckChunkJson();
  CheckBadMerges();
  // Chunk 1 of 1 is the whole refine, byte for byte: the same scans, the
  // same IMU samples.
  const ToolRun one = RunTool(Refine("--chunk 1 --of 1 --out " + dir_ + "/one"), dir_);
  ASSERT_EQ(one.exit_code, 0) << one.err;
  for (const char* f : {"/trajectory.tum", "/map.pcd"})
    EXPECT_EQ(ReadFile(dir_ + "/one" + f), ReadFile(dir_ + "/whole" + f)) << f;
}

TEST_F(RefineChunksCliTest, BadChunkParametersAreExit2WithOneLine) {
  const std::string out = " --out " + dir_ + "/bad";
  const struct {
    std::string args, names;
  } cases[] = {
      {Refine("--chunk 4 --of 3" + out), "--chunk 4"},
      {Refine("--chunk 0 --of 3" + out), "--chunk 0"},
      {Refine("--chunk 1 --of 0" + out), "--of 0"},
      {Refine("--chunk 1" + out), "--chunk needs --of"},
      {Refine("--chunk one --of 3" + out), "--chunk one"},
      {Refine("--chunk 1 --of 10" + out), "shorter than their overlap"},
      {Refine("--chunk 1 --of 200 --set refine.job_overlap_s=0" + out), "fewer than 10"},
  };
  for (const auto& c : cases) {
    const ToolRun r = RunTool(c.args, dir_);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(c.names), std::string::npos) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/bad/trajectory.tum"));
}

// A missing, repeated or foreign chunk: exit 2, one line, nothing written.
void RefineChunksCliTest::CheckBadMerges() {
  const std::string out = dir_ + "/merge_bad";
  ToolRun r = RunTool(MergeArgs({1, 3}, out), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("missing chunk 2 of 3"), std::string::npos) << r.err;
  r = RunTool(MergeArgs({1, 1, 2, 3}, out), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("given twice"), std::string::npos) << r.err;
  r = RunTool("merge --out " + out + " --chunks " + dir_ + "/whole", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(dir_ + "/whole/chunk.json"), std::string::npos) << r.err;
  // --map for chunks refined without one, or a map that cannot be read.
  const std::string map = dir_ + "/whole/map.pcd";
  r = RunTool(MergeArgs({1, 2, 3}, out) + " --map " + map, dir_);
  testing_cli::ExpectOneErrorLine(r, "merge", "--map " + map);
  EXPECT_NE(r.err.find("refined without --map"), std::string::npos) << r.err;

  // A chunk refined with other options (one round) does not merge with the others.
  const std::string foreign = dir_ + "/foreign2";
  ToolRun chunk = RunTool(Refine("--chunk 2 --of 3 --set refine.rounds=1 --out " + foreign), dir_);
  ASSERT_EQ(chunk.exit_code, 0) << chunk.err;
  r = RunTool("merge --out " + out + " --chunks " + ChunkDir(1) + " --chunks " + foreign +
                  " --chunks " + ChunkDir(3), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("options_hash"), std::string::npos) << r.err;
  // Chunks of another N.
  chunk = RunTool(Refine("--chunk 2 --of 2 --out " + dir_ + "/of2"), dir_);
  ASSERT_EQ(chunk.exit_code, 0) << chunk.err;
  r = RunTool("merge --out " + out + " --chunks " + ChunkDir(1) + " --chunks " + dir_ + "/of2" +
                  " --chunks " + ChunkDir(3), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("has of 2"), std::string::npos) << r.err;
  for (const ToolRun* run : {&r}) EXPECT_EQ(std::count(run->err.begin(), run->err.end(), '\n'), 1);
  EXPECT_FALSE(std::filesystem::exists(out + "/trajectory.tum"));
}

TEST_F(RefineChunksCliTest, AnInitCoveringPartOfTheRecordingRefinesThatPartAndSaysSo) {
  // The IESKF trajectory's first 8 s of the 14 s recording.
  const Tum init = ReadPositions(Init());
  const std::string part = dir_ + "/init_part.tum";
  {
    std::ofstream f(part);
    std::istringstream in(ReadFile(Init()));
    std::string line;
    while (std::getline(in, line))
      if (!line.empty() && line[0] != '#' && std::stod(line) <= init.t_s.front() + 8.0) f << line << "\n";
  }
  const std::string out = dir_ + "/part";
  const ToolRun r = RunTool(Refine("--chunk 2 --of 2 --out " + out, part), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("covers only part of the recording"), std::string::npos) << r.err;
  const auto summary = nlohmann::json::parse(ReadFile(out + "/summary.json"));
  EXPECT_FALSE(summary["init_coverage"]["complete"].get<bool>());
  EXPECT_GT(summary["init_coverage"]["scans_outside_init"].get<int>(), 40);
  const Tum refined = ReadPositions(out + "/trajectory.tum");
  ASSERT_FALSE(refined.t_s.empty());
  EXPECT_LE(refined.t_s.back(), init.t_s.front() + 8.0 + 1e-6);
  bool warned = false;
  for (const auto& w : summary["warnings"])
    warned |= w.get<std::string>().find("covers only part") != std::string::npos;
  EXPECT_TRUE(warned);
}

}  // namespace
}  // namespace rvlio
