// The named steps of batch refinement, one by one (refine/init.h,
// refine/chunks.h, refine/association.h, refine/problem.h), on the box-room
// scene of refine_scene.h; and the whole refinement giving the same bits
// with one thread and with two.
#include <cmath>
#include <random>
#include <set>

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include "refine_scene.h"
#include "rvlio/math/so3.h"
#include "rvlio/refine/association.h"
#include "rvlio/refine/chunks.h"
#include "rvlio/refine/init.h"
#include "rvlio/refine/problem.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::Vector3d;
using namespace refine_scene;  // MakeScene, Config, kT0, kScanNs

// ---- state initialization ----

TEST(RefineInit, SelectionKeepsUsableScansAndCountsTheOthers) {
  Scene s = MakeScene(7, 3);
  RefineInput& in = s.input;
  in.scans[1].points.resize(kRefineMinScanPoints - 1);  // too few points
  in.scans[4].t_end_ns = in.scans[3].t_end_ns;          // not after scan 3
  in.init.resize(6);                                    // scan 6 outside
  in.imu.erase(in.imu.begin(),                          // scan 0 not covered
               std::find_if(in.imu.begin(), in.imu.end(),
                            [&](const ImuSample& m) { return m.t_ns > in.scans[0].t_start_ns; }));
  ASSERT_TRUE(CheckRefineInput(in).ok());
  RefineStats stats;
  StatusOr<RefineSequence> seq = SelectRefineScans(in, &stats);
  ASSERT_TRUE(seq.ok()) << seq.status().message();
  EXPECT_EQ(seq->kept, (std::vector<int>{2, 3, 5}));
  EXPECT_EQ(seq->size(), 3);
  EXPECT_EQ(seq->scan(1).t_end_ns, in.scans[3].t_end_ns);
  EXPECT_EQ(stats.scans_input, 7);
  EXPECT_EQ(stats.scans_too_few_points, 1);
  EXPECT_EQ(stats.scans_out_of_order, 1);
  EXPECT_EQ(stats.scans_outside_init, 1);
  EXPECT_EQ(stats.scans_without_imu, 1);
  EXPECT_EQ(stats.scans_refined, 3);

  in.init.resize(1);  // only scan 0's stamp
  RefineStats few;
  StatusOr<RefineSequence> none = SelectRefineScans(in, &few);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(none.status().message().find("(need 2)"), std::string::npos);
  RefineInput empty;
  EXPECT_FALSE(CheckRefineInput(empty).ok());
}

// A resting IMU with attitude R and gyro bias: gravity comes out in the
// initial trajectory's frame, whatever that frame is.
TEST(RefineInit, GravityFromAStaticStartIsCarriedIntoTheInitialFrame) {
  const Eigen::Matrix3d R = test::Rz(0.7) * test::Rx(0.1) * test::Ry(-0.05);
  const Vector3d bg(0.01, -0.02, 0.005);
  std::vector<ImuSample> imu;
  for (TimeNs t = 0; t <= 3 * kNsPerSecond; t += 5000000)
    imu.push_back(ImuSample{t, R.transpose() * Vector3d(0, 0, 9.81), bg});
  ImuOptions options;
  for (const Eigen::Matrix3d& R_frame : {test::Rx(0.0), test::Rx(0.4)}) {
    Trajectory init;
    for (TimeNs t = 0; t <= 3 * kNsPerSecond; t += kNsPerSecond)
      init.push_back(StampedPose{t, Vector3d(1, 2, 3), Eigen::Quaterniond(R_frame * R)});
    const RefineGravity g = InitRefineGravity(imu, init, options);
    EXPECT_TRUE(g.from_static);
    EXPECT_FALSE(g.started_moving);
    EXPECT_TRUE(g.warning.empty());
    EXPECT_LT((g.g_world - R_frame * Vector3d(0, 0, -9.81)).norm(), 1e-6);
    EXPECT_LT((g.bg - bg).norm(), 1e-9);
  }
}

TEST(RefineInit, AMovingStartTakesNominalGravityWithAWarning) {
  const Scene s = MakeScene(5, 1);
  ImuOptions options;
  options.gravity = 9.8;
  const RefineGravity g = InitRefineGravity(s.input.imu, s.input.init, options);
  EXPECT_TRUE(g.started_moving);
  EXPECT_FALSE(g.from_static);
  EXPECT_EQ(g.g_world, Vector3d(0, 0, -9.8));
  EXPECT_EQ(g.bg, Vector3d::Zero());
  EXPECT_NE(g.warning.find("starts moving"), std::string::npos);
}

TEST(RefineInit, InitialStatesFollowTheInitialTrajectory) {
  const Scene s = MakeScene(6, 2);
  RefineStats stats;
  StatusOr<RefineSequence> seq = SelectRefineScans(s.input, &stats);
  ASSERT_TRUE(seq.ok());
  const Vector3d bg(0.001, 0.002, -0.003);
  const std::vector<RefineState> states = InitialRefineStates(*seq, s.input.init, bg);
  ASSERT_EQ(states.size(), 6u);
  for (size_t k = 0; k < states.size(); ++k) {
    EXPECT_EQ(states[k].t_ns, s.input.scans[k].t_end_ns);
    EXPECT_LT((states[k].T_world_imu().t - s.input.init[k].p_world_imu).norm(), 1e-12);
    const SpeedBiasBlock sb = states[k].SpeedBias();
    EXPECT_EQ(sb.bg, bg);
    EXPECT_EQ(sb.ba, Vector3d::Zero());
    EXPECT_EQ(sb.v_world_imu,
              FiniteDifferenceVelocity(s.input.init, states[k].t_ns, kRefineVelocityHalfWindowNs));
    EXPECT_TRUE(AllFinite(states[k]));
  }
}

TEST(RefineInit, AResumedStateMustMatchTheRefinedScans) {
  const Scene s = MakeScene(4, 2);
  RefineStats stats;
  const RefineSequence seq = SelectRefineScans(s.input, &stats).value();
  const std::vector<RefineState> initial = InitialRefineStates(seq, s.input.init, Vector3d::Zero());
  EXPECT_TRUE(CheckResumedStates(initial, initial).ok());
  std::vector<RefineState> shorter(initial.begin(), initial.end() - 1);
  EXPECT_NE(CheckResumedStates(shorter, initial).message().find("3 scan states"),
            std::string::npos);
  std::vector<RefineState> shifted = initial;
  shifted[2].t_ns += 1000;
  EXPECT_NE(CheckResumedStates(shifted, initial).message().find("state of scan 2"),
            std::string::npos);
  std::vector<RefineState> nan = initial;
  nan[1].speed_bias[4] = std::nan("");
  EXPECT_EQ(CheckResumedStates(nan, initial).code(), StatusCode::kInvalidInput);
}

// ---- chunking ----

TEST(RefineChunks, ChunksCoverTheSequenceWithOverlap) {
  EXPECT_EQ(MakeRefineChunks(30, 10),
            (std::vector<ScanRange>{{0, 10}, {8, 18}, {16, 26}, {24, 30}}));
  EXPECT_EQ(MakeRefineChunks(5, 10), (std::vector<ScanRange>{{0, 5}}));
  for (int n : {1, 11, 999, 2500}) {
    for (int chunk : {10, 37, 500}) {
      const std::vector<ScanRange> c = MakeRefineChunks(n, chunk);
      EXPECT_EQ(c.front().begin, 0);
      EXPECT_EQ(c.back().end, n);
      for (size_t i = 0; i < c.size(); ++i) {
        EXPECT_LE(c[i].size(), chunk);
        EXPECT_GT(c[i].size(), 0);
        if (i == 0) continue;
        EXPECT_GE(c[i - 1].end - c[i].begin, kRefineMinChunkOverlap) << n << " " << chunk;
        EXPECT_GT(c[i].begin, c[i - 1].begin);
      }
    }
  }
}

// ---- association round ----

RefineState StateAt(const Pose3& T, TimeNs t_ns) {
  RefineState s;
  s.t_ns = t_ns;
  PoseBlock(T).ToArray(s.pose.data());
  return s;
}

// Sources in the chunk within the window are attached (sorted by source);
// a source before the chunk carries its plane by its move since the map was
// built; others stay where the map put them.
TEST(RefineAssociation, SplitAttachesNearPlanesAndCarriesEarlierOnes) {
  const int k = 20, window = 5;
  const ScanRange chunk{10, 40};
  std::vector<Pose3> map_poses(50);
  std::vector<RefineState> states(50);
  for (int j = 0; j < 50; ++j) {
    map_poses[j] = Pose3(test::Rz(0.01 * j), Vector3d(j, 0, 0));
    states[j] = StateAt(map_poses[j], j);
  }
  const Pose3 moved(test::Rz(0.02) * test::Rx(0.01), Vector3d(0.1, -0.2, 0.05));
  states[8] = StateAt(moved * map_poses[8], 8);  // an earlier chunk moved scan 8
  ConstraintList list(6);
  const std::vector<int32_t> sources = {23, 8, 30, 45, 17, 23};
  for (size_t i = 0; i < list.size(); ++i) {
    list[i].normal_world = Vector3d(0, 0.6, 0.8);
    list[i].q_world = Vector3d(i, 1.0, 2.0);
    list[i].p_lidar = Vector3d(1, 2, 3);
  }
  ConstraintList fixed;
  std::vector<std::pair<int32_t, int>> attached;
  SplitScanConstraints(k, chunk, window, list, sources, states, map_poses, &fixed, &attached);
  EXPECT_EQ(attached, (std::vector<std::pair<int32_t, int>>{{17, 4}, {23, 0}, {23, 5}}));
  ASSERT_EQ(fixed.size(), 3u);  // sources 8 (carried), 30 (beyond the window), 45 (after)
  EXPECT_LT((fixed[0].normal_world - moved.R * list[1].normal_world).norm(), 1e-12);
  EXPECT_LT((fixed[0].q_world - moved * list[1].q_world).norm(), 1e-12);
  EXPECT_EQ(fixed[1].q_world, list[2].q_world);
  EXPECT_EQ(fixed[2].q_world, list[3].q_world);

  SplitScanConstraints(k, chunk, 0, list, sources, states, map_poses, &fixed, &attached);
  EXPECT_TRUE(attached.empty());  // window 0: every plane world-fixed
  EXPECT_EQ(fixed.size(), list.size());
}

struct Round {
  Scene scene;
  RefineSequence sequence;
  std::vector<RefineState> states;
};

Round MakeRound(int scans) {
  Round r{MakeScene(scans, 4), {}, {}};
  RefineStats stats;
  r.sequence = SelectRefineScans(r.scene.input, &stats).value();
  r.states = InitialRefineStates(r.sequence, r.scene.input.init, Vector3d::Zero());
  return r;
}

TEST(RefineAssociation, DeskewMapAndAssociationAreTheSameOnOneOrTwoThreads) {
  const Round r = MakeRound(8);
  const RefineConfig config = Config();
  RefineRoundMap one(config.map), two(config.map);
  DeskewRefineScans(r.sequence, r.states, test::Gravity(), config.T_imu_lidar, 1, &one.p_lidar_end);
  DeskewRefineScans(r.sequence, r.states, test::Gravity(), config.T_imu_lidar, 2, &two.p_lidar_end);
  ASSERT_EQ(one.p_lidar_end.size(), 8u);
  EXPECT_EQ(one.p_lidar_end, two.p_lidar_end);
  BuildRefineMap(r.states, config.T_imu_lidar, &one);
  BuildRefineMap(r.states, config.T_imu_lidar, &two);
  EXPECT_EQ(one.map.stats().entries, two.map.stats().entries);
  EXPECT_GT(one.map.stats().entries, 1000);
  ASSERT_EQ(one.map_poses.size(), 8u);
  EXPECT_EQ(one.map_poses[3].t, r.states[3].T_world_imu().t);

  const ScanRange chunk{2, 8};
  const ChunkAssociation a = AssociateRefineChunk(config, one, r.states, chunk, 1, nullptr);
  const ChunkAssociation b = AssociateRefineChunk(config, two, r.states, chunk, 2, nullptr);
  ASSERT_EQ(a.factors.size(), 6u);
  EXPECT_GT(a.constraints, 6 * 300);
  EXPECT_EQ(a.points, b.points);
  EXPECT_EQ(a.constraints, b.constraints);
  for (int i = 0; i < chunk.size(); ++i) {
    ASSERT_EQ(static_cast<bool>(a.factors[i].fixed), static_cast<bool>(b.factors[i].fixed));
    ASSERT_EQ(a.factors[i].pairs.size(), b.factors[i].pairs.size());
    for (size_t p = 0; p < a.factors[i].pairs.size(); ++p) {
      const int j = a.factors[i].pairs[p].first;
      EXPECT_EQ(j, b.factors[i].pairs[p].first);
      EXPECT_TRUE(chunk.Contains(j));  // attached planes live in the chunk
      const std::vector<std::vector<double>> x = {
          std::vector<double>(r.states[chunk.begin + i].pose.begin(),
                              r.states[chunk.begin + i].pose.end()),
          std::vector<double>(r.states[j].pose.begin(), r.states[j].pose.end())};
      EXPECT_EQ(test::EvaluateCost(*a.factors[i].pairs[p].second, x),
                test::EvaluateCost(*b.factors[i].pairs[p].second, x));
    }
  }
  // A stop request before the first scan leaves nothing associated.
  const ChunkAssociation stopped =
      AssociateRefineChunk(config, one, r.states, chunk, 2, [] { return true; });
  EXPECT_EQ(stopped.constraints, 0);
}

TEST(RefineAssociation, ReleaseFreesTheAssociatedScansThenTheMap) {
  const Round r = MakeRound(8);
  const RefineConfig config = Config();
  RefineRoundMap round(config.map);
  DeskewRefineScans(r.sequence, r.states, test::Gravity(), config.T_imu_lidar, 1,
                    &round.p_lidar_end);
  BuildRefineMap(r.states, config.T_imu_lidar, &round);
  const int64_t entries = round.map.stats().entries;
  ASSERT_GT(entries, 0);
  ReleaseAssociatedScans(ScanRange{0, 5}, 4, &round);  // the next chunk starts at 4
  for (int k = 0; k < 8; ++k) EXPECT_EQ(round.p_lidar_end[k].empty(), k < 4) << k;
  EXPECT_EQ(round.map.stats().entries, entries);       // later chunks still read it
  ReleaseAssociatedScans(ScanRange{4, 8}, 8, &round);  // the last chunk
  for (int k = 0; k < 8; ++k) EXPECT_TRUE(round.p_lidar_end[k].empty()) << k;
  EXPECT_EQ(round.map.stats().entries, 0);
  ScanNeighbors nb;
  EXPECT_EQ(round.map.KNearest(r.states[0].T_world_imu().t, 1, 100.0, 0, &nb), 0);
}

// ---- problem build and solve ----

// The round's deskewed scans and map at the round's states.
void PrepareRound(const Round& r, const RefineConfig& config, int threads, RefineRoundMap* round) {
  DeskewRefineScans(r.sequence, r.states, test::Gravity(), config.T_imu_lidar, threads,
                    &round->p_lidar_end);
  BuildRefineMap(r.states, config.T_imu_lidar, round);
}

TEST(RefineProblem, ChunkProblemHoldsItsFirstPoseAndLinksEveryScan) {
  Round r = MakeRound(8);
  const RefineConfig config = Config();
  RefineRoundMap round(config.map);
  PrepareRound(r, config, 2, &round);
  const ScanRange chunk{3, 8};
  ChunkAssociation a = AssociateRefineChunk(config, round, r.states, chunk, 2, nullptr);
  int plane_blocks = 0;
  for (const ScanFactors& f : a.factors)
    plane_blocks += (f.fixed ? 1 : 0) + static_cast<int>(f.pairs.size());
  PoseManifold manifold;
  ceres::Problem problem(RefineProblemOptions());
  const ImuNoise noise = ImuNoise::FromOptions(config.imu);
  BuildRefineChunkProblem(r.sequence, noise, test::Gravity(), chunk, /*hold_first_pose=*/true, &a.factors, &manifold,
                          &r.states, &problem);
  EXPECT_EQ(problem.NumResidualBlocks(), plane_blocks + chunk.size() - 1);
  EXPECT_EQ(problem.NumParameterBlocks(), 2 * chunk.size());
  EXPECT_TRUE(problem.IsParameterBlockConstant(r.states[3].pose.data()));
  EXPECT_FALSE(problem.IsParameterBlockConstant(r.states[4].pose.data()));
  EXPECT_FALSE(problem.HasParameterBlock(r.states[2].pose.data()));

  const std::vector<RefineState> before = r.states;
  const RefineSolveReport rep =
      SolveRefineProblem(&problem, RefineSolver::Make(2).Options(10), chunk, nullptr, &r.states);
  EXPECT_TRUE(rep.accepted) << rep.message;
  EXPECT_LT(rep.cost_after, rep.cost_before);
  EXPECT_GT(rep.iterations, 0);
  EXPECT_EQ(r.states[3].pose, before[3].pose);              // held
  EXPECT_EQ(r.states[2].speed_bias, before[2].speed_bias);  // outside the chunk
  EXPECT_NE(r.states[5].pose, before[5].pose);
}

// The degeneracy stage of refine: none adds no prior and calls no scan
// degenerate; remap with its threshold above every eigenvalue holds all six
// directions of every scan, one prior per scan, and the poses then stay at
// their initial (anchor) values: they move by less than 5 % of what the
// same solve without the priors moves them.
TEST(RefineProblem, DegeneracyPriorsHoldThePosesAtTheirInitialValues) {
  {
    Round r = MakeRound(6);
    RefineConfig config = Config();
    config.degeneracy.method = DegeneracyMethod::kNone;
    RefineRoundMap round(config.map);
    PrepareRound(r, config, 1, &round);
    const ChunkAssociation a = AssociateRefineChunk(config, round, r.states, {0, 6}, 1, nullptr);
    EXPECT_EQ(a.degenerate_scans, 0);
    for (const ScanFactors& f : a.factors) {
      EXPECT_FALSE(f.has_degeneracy_prior);
      EXPECT_EQ(f.degeneracy.method, DegeneracyMethod::kNone);
    }
  }
  // Every direction held, and the same chunk without the priors.
  RefineConfig config = Config();
  config.degeneracy.method = DegeneracyMethod::kRemap;
  ASSERT_EQ(config.degeneracy.remap_refine_form, RemapWindowForm::kHold);  // the default
  config.degeneracy.remap_min_eigenvalue = 1e15;  // every direction degenerate
  double moved[2] = {0.0, 0.0};                    // largest motion from the anchors, m
  for (bool with_priors : {false, true}) {
    Round r = MakeRound(6);
    RefineRoundMap round(config.map);
    PrepareRound(r, config, 1, &round);
    const ScanRange chunk{0, 6};
    ChunkAssociation a = AssociateRefineChunk(config, round, r.states, chunk, 1, nullptr);
    EXPECT_EQ(a.degenerate_scans, 6);
    std::vector<PoseBlock> anchors;
    for (const RefineState& s : r.states) anchors.push_back(PoseBlock::FromArray(s.pose.data()));
    PoseManifold manifold;
    ceres::Problem problem(RefineProblemOptions());
    BuildRefineChunkProblem(r.sequence, ImuNoise::FromOptions(config.imu), test::Gravity(), chunk,
                            /*hold_first_pose=*/true, &a.factors, &manifold, &r.states, &problem);
    const int blocks = problem.NumResidualBlocks();
    if (with_priors) {
      AddRefineDegeneracyPriors(chunk, a.factors, anchors, &r.states, &problem);
      EXPECT_EQ(problem.NumResidualBlocks(), blocks + 6);
    }
    const RefineSolveReport rep =
        SolveRefineProblem(&problem, RefineSolver::Make(1).Options(10), chunk, nullptr, &r.states);
    ASSERT_TRUE(rep.accepted) << rep.message;
    for (int k = 1; k < 6; ++k) {
      const PoseBlock::Tangent d = Minus(PoseBlock::FromArray(r.states[k].pose.data()), anchors[k]);
      moved[with_priors] = std::max(moved[with_priors], d.tail<3>().norm());
    }
  }
  // The priors (lidar_noise / 1000) hold against the scans; what is left is
  // the pull of the IMU factors, stiffer here than the scans.
  EXPECT_GT(moved[0], 0.05);
  EXPECT_LT(moved[1], 0.05 * moved[0]);
}

// remap in the project form (degeneracy.remap_refine_form): with every
// direction weak, each scan's factors are constant in its own pose and in
// the poses of the scans whose planes it uses, so they cannot move any; the
// poses follow the IMU chain from the held first pose, as in the same chunk
// without any scan factor. No prior is added. A chunk of one scan has no IMU
// chain and gets the hold prior instead.
TEST(RefineProblem, RemapProjectFormLeavesTheWeakDirectionsToTheImuChain) {
  RefineConfig config = Config();
  config.degeneracy.method = DegeneracyMethod::kRemap;
  config.degeneracy.remap_min_eigenvalue = 1e15;  // every direction degenerate
  config.degeneracy.remap_refine_form = RemapWindowForm::kProject;
  const ScanRange chunk{0, 6};
  std::vector<RefineState> solved[2];  // projected scans; IMU chain only
  for (bool imu_only : {false, true}) {
    Round r = MakeRound(6);
    RefineRoundMap round(config.map);
    PrepareRound(r, config, 1, &round);
    ChunkAssociation a = AssociateRefineChunk(config, round, r.states, chunk, 1, nullptr);
    EXPECT_EQ(a.degenerate_scans, 6);
    for (ScanFactors& f : a.factors) {
      EXPECT_FALSE(f.has_degeneracy_prior);
      EXPECT_EQ(f.remap_held.cols(), 6);
      if (imu_only) f = ScanFactors();
    }
    PoseManifold manifold;
    ceres::Problem problem(RefineProblemOptions());
    BuildRefineChunkProblem(r.sequence, ImuNoise::FromOptions(config.imu), test::Gravity(), chunk,
                            /*hold_first_pose=*/true, &a.factors, &manifold, &r.states, &problem);
    ASSERT_TRUE(SolveRefineProblem(&problem, RefineSolver::Make(1).Options(10), chunk, nullptr,
                                   &r.states)
                    .accepted);
    solved[imu_only] = r.states;
  }
  for (int k = 1; k < 6; ++k) {
    const PoseBlock::Tangent d = Minus(PoseBlock::FromArray(solved[0][k].pose.data()),
                                       PoseBlock::FromArray(solved[1][k].pose.data()));
    EXPECT_LT(d.norm(), 1e-6) << k;
  }
  // One scan: no IMU factor would place it, so the pose is held.
  Round r = MakeRound(6);
  RefineRoundMap round(config.map);
  PrepareRound(r, config, 1, &round);
  const ChunkAssociation one = AssociateRefineChunk(config, round, r.states, {2, 3}, 1, nullptr);
  ASSERT_EQ(one.factors.size(), 1u);
  EXPECT_TRUE(one.factors[0].has_degeneracy_prior);
  EXPECT_EQ(one.factors[0].remap_held.cols(), 0);
}

// A residual whose evaluation fails: Ceres gives no usable solution.
class FailingCost : public ceres::SizedCostFunction<1, 9> {
 public:
  bool Evaluate(double const* const*, double*, double**) const override { return false; }
};

TEST(RefineProblem, ARejectedSolveRestoresTheStates) {
  Round r = MakeRound(4);
  for (RefineState& s : r.states) s.speed_bias[0] = 0.5;
  const std::vector<RefineState> before = r.states;
  ceres::Problem problem;
  problem.AddResidualBlock(new FailingCost, nullptr, r.states[1].speed_bias.data());
  const RefineSolveReport rep = SolveRefineProblem(&problem, RefineSolver::Make(1).Options(5),
                                                   ScanRange{0, 4}, nullptr, &r.states);
  EXPECT_FALSE(rep.accepted);
  EXPECT_FALSE(rep.message.empty());
  for (size_t k = 0; k < before.size(); ++k)
    EXPECT_EQ(r.states[k].speed_bias, before[k].speed_bias);
}

// With the true poses held, the IMU-only solve recovers the velocities from
// a zero start.
TEST(RefineProblem, VelocityAndBiasSolveRecoversTheVelocities) {
  Round r = MakeRound(10);
  for (size_t k = 0; k < r.states.size(); ++k) {
    PoseBlock(r.scene.truth[k]).ToArray(r.states[k].pose.data());
    for (double& x : r.states[k].speed_bias) x = 0.0;
  }
  const std::vector<RefineState> before = r.states;
  const RefineConfig config = Config();
  const RefineSolveReport rep =
      SolveVelocityAndBias(r.sequence, ImuNoise::FromOptions(config.imu), test::Gravity(),
                           RefineSolver::Make(2), &r.states);
  ASSERT_TRUE(rep.accepted) << rep.message;
  for (size_t k = 0; k < r.states.size(); ++k) {
    EXPECT_EQ(r.states[k].pose, before[k].pose) << k;  // held
    const Vector3d v_true = test::Swing(NsToSeconds(r.states[k].t_ns)).v;
    EXPECT_LT((r.states[k].SpeedBias().v_world_imu - v_true).norm(), 0.02) << k;
  }
}

// ---- the whole refinement ----

TEST(RefineSteps, RefineIsBitIdenticalOnOneAndTwoThreads) {
  RefineConfig one = Config(), two = Config();
  one.refine.rounds = two.refine.rounds = 2;
  one.refine.chunk_scans = two.refine.chunk_scans = 10;
  one.refine.threads = 1;
  two.refine.threads = 2;
  StatusOr<RefineResult> a = Refine(one, MakeScene(16, 7).input);
  StatusOr<RefineResult> b = Refine(two, MakeScene(16, 7).input);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->threads, 1);
  EXPECT_EQ(b->threads, 2);
  EXPECT_EQ(a->rounds.front().chunks, 2);
  ASSERT_EQ(a->trajectory.size(), b->trajectory.size());
  for (size_t k = 0; k < a->trajectory.size(); ++k) {
    EXPECT_EQ(a->trajectory[k].p_world_imu, b->trajectory[k].p_world_imu) << k;
    EXPECT_EQ(a->trajectory[k].q_world_imu.coeffs(), b->trajectory[k].q_world_imu.coeffs()) << k;
  }
  EXPECT_EQ(a->map, b->map);
  EXPECT_EQ(a->rounds.back().constraints, b->rounds.back().constraints);
}

}  // namespace
}  // namespace rvlio
