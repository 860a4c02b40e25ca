// Batch refinement on a synthetic oracle: noise-free scans of a box room
// with furniture-free walls, taken along the closed-form motion of
// smoother_test_util.h with per-point times (motion distortion included), and
// noise-free IMU samples. From a drifting, noisy initial trajectory the
// refined one recovers the truth far better than where it started, with and
// without chunking; bad input is InvalidInput.
#include <atomic>
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"
#include "rvlio/refine/refine.h"
#include "refine_scene.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;

using namespace refine_scene;  // MakeScene, Config, kT0, kScanNs

struct Errors {
  double position_rmse = 0.0;  // m
  double rotation_rmse = 0.0;  // deg
};

Errors Compare(const Trajectory& est, const std::vector<Pose3>& truth) {
  EXPECT_EQ(est.size(), truth.size());
  Errors e;
  for (size_t k = 0; k < est.size() && k < truth.size(); ++k) {
    e.position_rmse += (est[k].p_world_imu - truth[k].t).squaredNorm();
    const double a = so3::Log(truth[k].R.transpose() * est[k].q_world_imu.toRotationMatrix()).norm();
    e.rotation_rmse += a * a;
  }
  e.position_rmse = std::sqrt(e.position_rmse / est.size());
  e.rotation_rmse = std::sqrt(e.rotation_rmse / est.size()) * 180.0 / M_PI;
  return e;
}

TEST(Refine, RecoversTheTruthFromADriftingInitialTrajectory) {
  Scene scene = MakeScene(30, 5);
  const Errors before = Compare(scene.input.init, scene.truth);
  int reported = 0;
  StatusOr<RefineResult> r =
      Refine(Config(), std::move(scene.input), [&](const RefineRound&) { ++reported; });
  ASSERT_TRUE(r.ok()) << r.status().message();
  const Errors after = Compare(r->trajectory, scene.truth);
  EXPECT_GT(before.position_rmse, 0.08);  // what there is to correct
  EXPECT_LT(after.position_rmse, 0.01) << "before " << before.position_rmse;
  EXPECT_LT(after.position_rmse, 0.1 * before.position_rmse);
  EXPECT_LT(after.rotation_rmse, 0.1) << "before " << before.rotation_rmse;
  EXPECT_LT(after.rotation_rmse, 0.25 * before.rotation_rmse);
  // The report: rounds with falling cost, moves shrinking, constraints found.
  ASSERT_FALSE(r->rounds.empty());
  EXPECT_EQ(reported, static_cast<int>(r->rounds.size()));
  const RefineRound& first = r->rounds.front();
  EXPECT_LT(first.cost_after, first.cost_before);
  EXPECT_GT(first.constraints, 30 * 500);
  EXPECT_EQ(first.chunks, 1);
  EXPECT_LT(r->rounds.back().max_translation_change_m, first.max_translation_change_m);
  EXPECT_EQ(r->stats.scans_refined, 30);
  EXPECT_FALSE(r->stats.gravity_from_static);  // the motion never rests
  EXPECT_NE(r->linear_solver.find("SPARSE_NORMAL_CHOLESKY"), std::string::npos);
  EXPECT_GT(r->map.size(), 1000u);
  // Each map point is one return with its own attributes: its scan index is
  // a row of the trajectory, and its intensity names the return whose time
  // and ring it has.
  ASSERT_TRUE(r->map.Consistent());
  ASSERT_TRUE(r->map.has_intensity && r->map.has_time && r->map.has_ring && r->map.has_scan_index);
  for (size_t i = 0; i < r->map.size(); ++i) {
    const uint32_t k = r->map.scan_index[i];
    ASSERT_LT(k, r->trajectory.size());
    const int ret = static_cast<int>(r->map.intensity[i]);
    EXPECT_EQ(r->map.t_ns[i], ReturnTime(r->trajectory[k].t_ns - kScanNs, ret, 1500)) << i;
    EXPECT_EQ(r->map.ring[i], ret % 16) << i;
  }
  // Velocities and biases: the truth has none.
  for (size_t k = 0; k < r->v_world_imu.size(); ++k) {
    EXPECT_LT((r->v_world_imu[k] - test::Swing(NsToSeconds(kT0 + k * kScanNs)).v).norm(), 0.05);
    EXPECT_LT(r->gyro_bias[k].norm(), 0.01);
  }
}

// Chunks hold their first pose at the previous chunk's result and see the
// planes of later chunks at their estimates from the start of the round, so
// in this room (every scan sees every wall) they converge more slowly than
// one problem: a smaller, IESKF-like initial error (~5 cm).
TEST(Refine, ChunksOfTenScansAlsoRecoverTheTruth) {
  Scene scene = MakeScene(30, 9, 0.3);
  const Errors before = Compare(scene.input.init, scene.truth);
  RefineConfig c = Config();
  c.refine.chunk_scans = 10;
  StatusOr<RefineResult> r = Refine(c, std::move(scene.input));
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rounds.front().chunks, 4);  // [0,10) [8,18) [16,26) [24,30)
  const Errors after = Compare(r->trajectory, scene.truth);
  EXPECT_GT(before.position_rmse, 0.04);
  EXPECT_LT(after.position_rmse, 0.015) << "before " << before.position_rmse;
  EXPECT_LT(after.position_rmse, 0.3 * before.position_rmse);
}

// The plane-to-source attachment is what makes the rounds converge fast
// (refine/pair_factor.h): with world-fixed planes only (refine_plane_window 0)
// the same rounds leave a clearly larger error on the drifting start.
TEST(Refine, PlanesMovingWithTheirScansConvergeFasterThanAWorldFixedMap) {
  RefineConfig fixed_map = Config();
  fixed_map.refine.plane_window = 0;
  Scene a = MakeScene(30, 5), b = MakeScene(30, 5);
  StatusOr<RefineResult> ra = Refine(fixed_map, std::move(a.input));
  StatusOr<RefineResult> rb = Refine(Config(), std::move(b.input));
  ASSERT_TRUE(ra.ok() && rb.ok());
  const double e_fixed = Compare(ra->trajectory, a.truth).position_rmse;
  const double e_joint = Compare(rb->trajectory, b.truth).position_rmse;
  EXPECT_LT(e_joint, 0.25 * e_fixed) << "fixed map " << e_fixed << ", joint " << e_joint;
}

// Summarized pair and world-plane factors (refine.summarize_pairs,
// refine/pair_factor.h) have the exact factors' cost, gradient and
// Gauss-Newton Hessian: the refined trajectories agree to rounding, far
// below the error left.
TEST(Refine, SummarizedFactorsAgreeWithExactFactors) {
  RefineConfig exact = Config(), summarized = Config();
  exact.refine.summarize_pairs = false;
  summarized.refine.summarize_pairs = true;
  summarized.refine.chunk_scans = exact.refine.chunk_scans = 12;  // fixed planes too
  Scene a = MakeScene(30, 5), b = MakeScene(30, 5);
  StatusOr<RefineResult> ra = Refine(exact, std::move(a.input));
  StatusOr<RefineResult> rb = Refine(summarized, std::move(b.input));
  ASSERT_TRUE(ra.ok() && rb.ok());
  ASSERT_EQ(ra->trajectory.size(), rb->trajectory.size());
  double max_dp = 0.0, max_dq = 0.0;
  for (size_t k = 0; k < ra->trajectory.size(); ++k) {
    max_dp = std::max(max_dp, (ra->trajectory[k].p_world_imu - rb->trajectory[k].p_world_imu).norm());
    max_dq = std::max(max_dq, ra->trajectory[k].q_world_imu.angularDistance(rb->trajectory[k].q_world_imu));
  }
  EXPECT_LT(max_dp, 1e-6);  // m
  EXPECT_LT(max_dq, 1e-6);  // rad
  ASSERT_EQ(ra->rounds.size(), rb->rounds.size());
  EXPECT_NEAR(rb->rounds.front().cost_before, ra->rounds.front().cost_before,
              1e-8 * ra->rounds.front().cost_before);
  EXPECT_EQ(rb->rounds.front().constraints, ra->rounds.front().constraints);
}

TEST(Refine, BadInputIsInvalidInputWithAClearMessage) {
  {
    Scene scene = MakeScene(5, 1);
    for (auto& p : scene.input.init) p.t_ns += 100 * kNsPerSecond;  // far later
    StatusOr<RefineResult> r = Refine(Config(), std::move(scene.input));
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(r.status().message().find("does not overlap"), std::string::npos)
        << r.status().message();
  }
  {
    Scene scene = MakeScene(5, 1);
    scene.input.imu.clear();
    StatusOr<RefineResult> r = Refine(Config(), std::move(scene.input));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("IMU"), std::string::npos);
  }
  {
    Scene scene = MakeScene(5, 1);
    scene.input.init.resize(1);  // covers only the first scan
    StatusOr<RefineResult> r = Refine(Config(), std::move(scene.input));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("4 outside the initial trajectory"), std::string::npos)
        << r.status().message();
  }
  {
    RefineInput empty;
    EXPECT_FALSE(Refine(Config(), std::move(empty)).ok());
  }
}

// RefineHooks: the state after a round continues bit for bit; a stop request
// ends with the last completed round's result (what that many rounds give).
TEST(Refine, ResumedFromARoundStateEqualsTheUninterruptedResult) {
  RefineConfig config = Config();
  config.refine.rounds = 3;
  std::vector<RefineRoundState> states;
  RefineHooks record;
  record.on_state = [&](const RefineRoundState& s) {
    states.push_back(s);
    return Status::Ok();
  };
  StatusOr<RefineResult> full = Refine(config, MakeScene(12, 7).input, record);
  ASSERT_TRUE(full.ok()) << full.status().message();
  ASSERT_EQ(full->rounds.size(), 3u);
  ASSERT_EQ(states.size(), 4u);  // the initialization, then each round
  EXPECT_EQ(states[0].rounds_done, 0);
  EXPECT_EQ(states[3].rounds_done, 3);
  for (int from : {0, 1, 2}) {
    RefineHooks hooks;
    hooks.resume = &states[from];
    StatusOr<RefineResult> resumed = Refine(config, MakeScene(12, 7).input, hooks);
    ASSERT_TRUE(resumed.ok()) << resumed.status().message();
    ASSERT_EQ(resumed->trajectory.size(), full->trajectory.size());
    for (size_t k = 0; k < full->trajectory.size(); ++k) {
      EXPECT_EQ(resumed->trajectory[k].p_world_imu, full->trajectory[k].p_world_imu) << from;
      EXPECT_EQ(resumed->trajectory[k].q_world_imu.coeffs(), full->trajectory[k].q_world_imu.coeffs());
      EXPECT_EQ(resumed->v_world_imu[k], full->v_world_imu[k]);
    }
    EXPECT_EQ(resumed->map, full->map);
    EXPECT_EQ(resumed->rounds.size(), 3u);
  }
  // A state of another input is refused.
  RefineHooks other;
  other.resume = &states[1];
  StatusOr<RefineResult> wrong = Refine(config, MakeScene(10, 7).input, other);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.status().message().find("scan states"), std::string::npos)
      << wrong.status().message();

  // Stop requested in the middle of round 2 (the 5th poll after round 1:
  // within the association or the solve): round 2 is dropped, the result is
  // round 1's.
  int rounds_seen = 0;
  std::atomic<int> polls_after_round_1{0};  // polled from the association threads too
  RefineHooks stop;
  stop.on_round = [&](const RefineRound&) { ++rounds_seen; };
  stop.stop = [&] { return rounds_seen >= 1 && ++polls_after_round_1 >= 5; };
  StatusOr<RefineResult> stopped = Refine(config, MakeScene(12, 7).input, stop);
  ASSERT_TRUE(stopped.ok());
  EXPECT_TRUE(stopped->stopped);
  EXPECT_EQ(stopped->rounds.size(), 1u);
  config.refine.rounds = 1;
  StatusOr<RefineResult> one = Refine(config, MakeScene(12, 7).input);
  ASSERT_TRUE(one.ok());
  EXPECT_FALSE(one->stopped);
  for (size_t k = 0; k < one->trajectory.size(); ++k)
    EXPECT_EQ(stopped->trajectory[k].p_world_imu, one->trajectory[k].p_world_imu);
}

}  // namespace
}  // namespace rvlio
