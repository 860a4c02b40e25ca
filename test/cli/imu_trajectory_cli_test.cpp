// output.imu_trajectory end to end on a 6 s simulated tunnel (the recording
// MapLasCli simulates): `run` with either backend, `refine --chunk K --of 2`
// and `merge` write trajectory_imu.tum, a pose at every 200 Hz IMU sample
// between the first and last scan end and at every scan end, equal to
// trajectory.tum at the scan ends and as accurate against the ground truth;
// without the key nothing changes (docs/outputs.md "trajectory_imu.tum").
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

#include <gtest/gtest.h>

#include "cli_util.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace imu_trajectory_cli {  // named: the test folder compiles as one unit (unity build)

using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

constexpr double kSimImuHz = 200.0;  // the simulator's imu.rate
const char* const kImuTrajectory = " --set output.imu_trajectory=true";

Trajectory Read(const std::string& path) {
  StatusOr<Trajectory> t = ReadTum(path);
  EXPECT_TRUE(t.ok()) << t.status().message();
  return t.ok() ? *t : Trajectory();
}

double Ate(const Trajectory& truth, const Trajectory& est) {
  StatusOr<EvalResult> e = Evaluate(truth, est, EvalOptions());
  EXPECT_TRUE(e.ok()) << e.status().message();
  return e.ok() ? e->ape_m.rmse : NAN;
}

// trajectory_imu.tum of `dir` against its trajectory.tum and the truth:
// one pose per IMU sample over the span plus the scan ends, the scan ends'
// poses those of trajectory.tum, the error against the truth close to
// trajectory.tum's (`slack_m`).
void CheckImuTrajectory(const std::string& dir, const Trajectory& truth, double slack_m) {
  SCOPED_TRACE(dir);
  const Trajectory scans = Read(dir + "/trajectory.tum");
  const Trajectory imu = Read(dir + "/trajectory_imu.tum");
  if (scans.empty() || imu.empty()) return;
  EXPECT_EQ(imu.front().t_ns, scans.front().t_ns);
  EXPECT_EQ(imu.back().t_ns, scans.back().t_ns);
  std::map<TimeNs, const StampedPose*> by_stamp;
  for (size_t i = 0; i < imu.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(imu[i].t_ns, imu[i - 1].t_ns) << i;
    }
    by_stamp[imu[i].t_ns] = &imu[i];
  }
  for (const StampedPose& s : scans) {
    const auto it = by_stamp.find(s.t_ns);
    ASSERT_NE(it, by_stamp.end()) << "no pose at the scan end " << s.t_ns;
    EXPECT_LT((it->second->p_world_imu - s.p_world_imu).norm(), 1e-8) << s.t_ns;
    EXPECT_LT(it->second->q_world_imu.angularDistance(s.q_world_imu), 1e-9) << s.t_ns;
  }
  const double span_s = NsToSeconds(scans.back().t_ns - scans.front().t_ns);
  const double samples = span_s * kSimImuHz;  // the IMU samples over the span, +-1
  EXPECT_GE(static_cast<double>(imu.size()), samples - 1.0);
  EXPECT_LE(static_cast<double>(imu.size()), samples + 1.0 + static_cast<double>(scans.size()));
  // Every gap one IMU period or less (a scan end between two samples splits one).
  for (size_t i = 1; i < imu.size(); ++i)
    EXPECT_LE(imu[i].t_ns - imu[i - 1].t_ns, SecondsToNs(1.0 / kSimImuHz)) << i;
  const double ate_scans = Ate(truth, scans), ate_imu = Ate(truth, imu);
  std::printf("%s: %zu scan poses ATE %.4f m, %zu IMU-rate poses ATE %.4f m\n", dir.c_str(),
              scans.size(), ate_scans, imu.size(), ate_imu);
  EXPECT_LT(ate_imu, ate_scans + slack_m);
}

class ImuTrajectoryCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing_cli::MakeTempDir("rvlio_imu_trajectory");
    ASSERT_FALSE(dir_.empty());
    const ToolRun sim = testing_cli::SimulateTunnel(dir_ + "/sim", 3, 6, dir_);
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    truth_ = Read(dir_ + "/sim/tunnel_gt.tum");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string Input() const {
    return "--bag " + dir_ + "/sim/tunnel.bag --config " + dir_ + "/sim/tunnel.yaml";
  }
  ToolRun Run(const std::string& out, const std::string& extra) const {
    return RunTool("run " + Input() + " --out " + dir_ + "/" + out + " " + extra, dir_);
  }
  ToolRun RefineChunk(int k, const std::string& extra) const {
    return RunTool("refine " + Input() + " --init " + dir_ + "/ieskf/trajectory.tum --chunk " +
                       std::to_string(k) + " --of 2 --out " + dir_ + "/chunk" + std::to_string(k) +
                       " --set refine.rounds=2 --set refine.job_overlap_s=1.5" + extra,
                   dir_);
  }

  std::string dir_;
  Trajectory truth_;
};

TEST_F(ImuTrajectoryCli, RunRefineAndMergeWriteTheImuRateTrajectoryOnlyWhenAsked) {
  ToolRun r = Run("plain", "--set backend=ieskf");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Run("ieskf", "--set backend=ieskf" + std::string(kImuTrajectory));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = Run("smoother", "--set backend=smoother" + std::string(kImuTrajectory));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Without the key: no trajectory_imu.tum; with it the other outputs are the same.
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/plain/trajectory_imu.tum"));
  EXPECT_EQ(ReadFile(dir_ + "/plain/trajectory.tum"), ReadFile(dir_ + "/ieskf/trajectory.tum"));
  EXPECT_EQ(ReadFile(dir_ + "/plain/map.pcd"), ReadFile(dir_ + "/ieskf/map.pcd"));
  // The IESKF's propagated poses step onto each update (a few mm here); the
  // smoother's spread their end mismatch.
  CheckImuTrajectory(dir_ + "/ieskf", truth_, 0.003);
  CheckImuTrajectory(dir_ + "/smoother", truth_, 0.002);

  ASSERT_EQ((r = RefineChunk(1, kImuTrajectory)).exit_code, 0) << r.err;
  ASSERT_EQ((r = RefineChunk(2, kImuTrajectory)).exit_code, 0) << r.err;
  CheckImuTrajectory(dir_ + "/chunk1", truth_, 0.002);
  CheckImuTrajectory(dir_ + "/chunk2", truth_, 0.002);
  r = RunTool(
      "merge --chunks " + dir_ + "/chunk1 --chunks " + dir_ + "/chunk2 --out " + dir_ + "/merged",
      dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  CheckImuTrajectory(dir_ + "/merged", truth_, 0.002);

  // A chunk refined without the key: the merge says so and writes none.
  std::filesystem::copy(dir_ + "/chunk2", dir_ + "/chunk2_plain");
  std::filesystem::remove(dir_ + "/chunk2_plain/trajectory_imu.tum");
  nlohmann::json summary = nlohmann::json::parse(ReadFile(dir_ + "/chunk2_plain/summary.json"));
  ASSERT_EQ(summary["config"]["output"]["imu_trajectory"], true);
  summary["config"]["output"]["imu_trajectory"] = false;
  std::ofstream(dir_ + "/chunk2_plain/summary.json") << summary.dump(2);
  r = RunTool("merge --chunks " + dir_ + "/chunk1 --chunks " + dir_ + "/chunk2_plain --out " +
                  dir_ + "/mixed",
              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/mixed/trajectory_imu.tum"));
  EXPECT_NE(ReadFile(dir_ + "/mixed/summary.json").find("chunk(s) 2 were refined without"),
            std::string::npos);
  // Its trajectory_imu.tum missing while its summary asks for it: exit 2 naming the file.
  std::filesystem::remove(dir_ + "/chunk2/trajectory_imu.tum");
  r = RunTool(
      "merge --chunks " + dir_ + "/chunk1 --chunks " + dir_ + "/chunk2 --out " + dir_ + "/broken",
      dir_);
  testing_cli::ExpectOneErrorLine(r, "merge", "chunk2/trajectory_imu.tum");
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/broken"));
}

}  // namespace imu_trajectory_cli
}  // namespace rvlio
