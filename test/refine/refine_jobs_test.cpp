// Chunk jobs (refine/jobs.h): the spans cover the initial
// trajectory's time with the stated overlap, bad chunk parameters are
// InvalidInput, and the merge undoes each chunk's own rigid frame and leaves
// no step at the borders.
#include "rvlio/refine/jobs.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace rvlio {
namespace {

constexpr TimeNs kJobsT0 = 1000000000000;  // 1000 s
constexpr TimeNs kPeriod = 100000000;  // 10 Hz

TEST(RefineJobSpan, CoresTileTheSpanAndNeighboursShareTheOverlap) {
  const TimeNs t1 = kJobsT0 + SecondsToNs(30.0);
  const int n = 3;
  TimeNs previous_core_end = kJobsT0;
  for (int k = 1; k <= n; ++k) {
    StatusOr<RefineJobSpan> s = MakeRefineJobSpan(kJobsT0, t1, k, n, 4.0);
    ASSERT_TRUE(s.ok()) << s.status().message();
    EXPECT_EQ(s->core_begin_ns, previous_core_end);
    EXPECT_NEAR(NsToSeconds(s->core_end_ns - s->core_begin_ns), 10.0, 1e-9);
    EXPECT_EQ(s->begin_ns, k == 1 ? kJobsT0 : s->core_begin_ns - SecondsToNs(2.0));
    EXPECT_EQ(s->end_ns, k == n ? t1 : s->core_end_ns + SecondsToNs(2.0));
    previous_core_end = s->core_end_ns;
  }
  EXPECT_EQ(previous_core_end, t1);
  StatusOr<RefineJobSpan> one = MakeRefineJobSpan(kJobsT0, t1, 1, 1, 100.0);  // one chunk: no overlap needed
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one->begin_ns, kJobsT0);
  EXPECT_EQ(one->end_ns, t1);
}

TEST(RefineJobSpan, BadChunkParametersAreInvalidInputNamingTheOption) {
  const TimeNs t1 = kJobsT0 + SecondsToNs(30.0);
  struct Case {
    TimeNs t1;
    int chunk, count;
    double overlap_s;
    const char* names;
  };
  for (const Case& c : {Case{t1, 1, 0, 4.0, "--of 0"}, Case{t1, 4, 3, 4.0, "--chunk 4"},
                        Case{t1, 0, 3, 4.0, "--chunk 0"}, Case{t1, 1, 10, 4.0, "shorter than their overlap"},
                        Case{kJobsT0, 1, 1, 4.0, "spans no time"}}) {
    StatusOr<RefineJobSpan> s = MakeRefineJobSpan(kJobsT0, c.t1, c.chunk, c.count, c.overlap_s);
    ASSERT_FALSE(s.ok()) << c.names;
    EXPECT_EQ(s.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(s.status().message().find(c.names), std::string::npos) << s.status().message();
  }
}

// A curving 30 s trajectory at 10 Hz.
StampedPose TruthAt(TimeNs t_ns) {
  const double t = NsToSeconds(t_ns - kJobsT0);
  StampedPose p;
  p.t_ns = t_ns;
  p.p_world_imu = Eigen::Vector3d(1.5 * t, 4.0 * std::sin(0.1 * t), 0.3 * std::cos(0.2 * t));
  p.q_world_imu = Eigen::Quaterniond(Eigen::AngleAxisd(0.4 * std::sin(0.1 * t), Eigen::Vector3d::UnitZ()));
  return p;
}

// The chunks of the truth, each in its own frame (a different rigid
// transform per chunk) with `noise_m` of position noise.
std::vector<RefineJobTrajectory> ChunksOfTruth(int n, double overlap_s, double noise_m,
                                               TimeNs period_ns = kPeriod) {
  const TimeNs t1 = kJobsT0 + SecondsToNs(30.0);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<RefineJobTrajectory> chunks;
  for (int k = 1; k <= n; ++k) {
    RefineJobTrajectory c;
    c.span = MakeRefineJobSpan(kJobsT0, t1, k, n, overlap_s).value();
    const Pose3 T_chunk_world(Eigen::Quaterniond(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d(1, 2, 3).normalized())),
                              Eigen::Vector3d(0.2 * k, -0.1 * k, 0.05 * k));
    for (TimeNs t = kJobsT0; t <= t1; t += period_ns) {
      if (!c.span.Contains(t)) continue;
      StampedPose p = TruthAt(t);
      p.p_world_imu = T_chunk_world * p.p_world_imu +
                      Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      p.q_world_imu = Eigen::Quaterniond(T_chunk_world.R) * p.q_world_imu;
      c.trajectory.push_back(p);
    }
    chunks.push_back(c);
  }
  return chunks;
}

TEST(MergeRefineJobs, UndoesEachChunksFrameAndHasNoStepAtTheBorders) {
  const double noise_m = 0.002;
  const std::vector<RefineJobTrajectory> chunks = ChunksOfTruth(3, 4.0, noise_m);
  StatusOr<RefineJobMerge> merged = MergeRefineJobs(chunks);
  ASSERT_TRUE(merged.ok()) << merged.status().message();
  ASSERT_EQ(merged->trajectory.size(), 301u);  // every stamp once
  ASSERT_EQ(merged->alignments.size(), 3u);
  EXPECT_EQ(merged->alignments[1].shared_poses, 41);  // 4 s at 10 Hz, both ends included
  // Chunk 1's frame is the merged one: the truth through chunk 1's transform.
  const Pose3 T1(Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d(1, 2, 3).normalized())),
                 Eigen::Vector3d(0.2, -0.1, 0.05));
  double worst_m = 0.0, worst_step_change_m = 0.0;
  for (size_t i = 0; i < merged->trajectory.size(); ++i) {
    const StampedPose& p = merged->trajectory[i];
    worst_m = std::max(worst_m, (p.p_world_imu - T1 * TruthAt(p.t_ns).p_world_imu).norm());
    if (i >= 2) {  // the change of the step between consecutive poses
      const Eigen::Vector3d a = merged->trajectory[i - 1].p_world_imu - merged->trajectory[i - 2].p_world_imu;
      const Eigen::Vector3d b = p.p_world_imu - merged->trajectory[i - 1].p_world_imu;
      worst_step_change_m = std::max(worst_step_change_m, (b - a).norm());
    }
  }
  // Alignment error from 40 noisy poses is well under the noise; the curve's
  // own second difference is below 1 cm; noise adds up to ~4 sigma * 2.
  EXPECT_LT(worst_m, 5.0 * noise_m);
  EXPECT_LT(worst_step_change_m, 0.01 + 8.0 * noise_m);
  // Residual: the difference of two poses with independent noise, RMS
  // sqrt(6) sigma in 3-D, plus a 30% margin.
  for (int k = 1; k < 3; ++k)
    EXPECT_LT(merged->alignments[k].rms_residual_m, 1.3 * std::sqrt(6.0) * noise_m);
}

TEST(MergeRefineJobs, AMissingChunkOrTooShortAnOverlapIsInvalidInput) {
  std::vector<RefineJobTrajectory> chunks = ChunksOfTruth(3, 4.0, 0.0);
  std::vector<RefineJobTrajectory> missing = {chunks[0], chunks[2]};
  StatusOr<RefineJobMerge> m = MergeRefineJobs(missing);
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().code(), StatusCode::kInvalidInput);

  std::vector<RefineJobTrajectory> thin = ChunksOfTruth(3, 0.1, 0.0);  // one shared stamp at most
  m = MergeRefineJobs(thin);
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("chunks 1 and 2 share"), std::string::npos) << m.status().message();
}

// The chunks' denser trajectories (trajectory_imu.tum: here 50 Hz, the 10 Hz
// scan poses among them) merged by the scan poses' alignments: the merged
// scan poses at the scan stamps, the truth in chunk 1's frame elsewhere.
TEST(MergeAlignedTrajectories, MergesDenserTrajectoriesAsTheScanPoses) {
  const double noise_m = 0.002;
  const std::vector<RefineJobTrajectory> dense = ChunksOfTruth(3, 4.0, noise_m, kPeriod / 5);
  std::vector<RefineJobTrajectory> scans = dense;
  const auto between_scans = [](const StampedPose& p) { return (p.t_ns - kJobsT0) % kPeriod != 0; };
  for (RefineJobTrajectory& c : scans)
    c.trajectory.erase(
        std::remove_if(c.trajectory.begin(), c.trajectory.end(), between_scans),
        c.trajectory.end());
  const StatusOr<RefineJobMerge> merged = MergeRefineJobs(scans);
  ASSERT_TRUE(merged.ok()) << merged.status().message();
  const StatusOr<Trajectory> merged_dense = MergeAlignedTrajectories(dense, merged->alignments);
  ASSERT_TRUE(merged_dense.ok()) << merged_dense.status().message();
  ASSERT_EQ(merged_dense->size(), 1501u);  // every 20 ms stamp of 30 s once
  const Pose3 T1(Eigen::Quaterniond(Eigen::AngleAxisd(0.01, Eigen::Vector3d(1, 2, 3).normalized())),
                 Eigen::Vector3d(0.2, -0.1, 0.05));
  size_t at_scans = 0;
  for (const StampedPose& p : *merged_dense) {
    EXPECT_LT((p.p_world_imu - T1 * TruthAt(p.t_ns).p_world_imu).norm(), 5.0 * noise_m);
    if (between_scans(p)) continue;
    const StampedPose& s = merged->trajectory[at_scans++];
    ASSERT_EQ(s.t_ns, p.t_ns);
    EXPECT_EQ(s.p_world_imu, p.p_world_imu);
    EXPECT_EQ(s.q_world_imu.coeffs(), p.q_world_imu.coeffs());
  }
  EXPECT_EQ(at_scans, merged->trajectory.size());
  const std::vector<RefineJobAlignment> two(merged->alignments.begin(),
                                            merged->alignments.begin() + 2);
  EXPECT_EQ(MergeAlignedTrajectories(dense, two).status().code(), StatusCode::kInvalidInput);
}

TEST(BlendPoses, EndsAreTheInputsAndTheMiddleIsHalfway) {
  StampedPose a = TruthAt(kJobsT0), b = TruthAt(kJobsT0 + SecondsToNs(10.0));
  const StampedPose mid = BlendPoses(a, b, 0.5);
  EXPECT_TRUE(BlendPoses(a, b, 0.0).p_world_imu.isApprox(a.p_world_imu));
  EXPECT_TRUE(BlendPoses(a, b, 1.0).p_world_imu.isApprox(b.p_world_imu));
  EXPECT_TRUE(mid.p_world_imu.isApprox(0.5 * (a.p_world_imu + b.p_world_imu)));
  EXPECT_NEAR(mid.q_world_imu.angularDistance(a.q_world_imu),
              mid.q_world_imu.angularDistance(b.q_world_imu), 1e-12);
}

}  // namespace
}  // namespace rvlio
