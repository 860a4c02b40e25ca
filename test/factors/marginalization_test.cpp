// Marginalization prior: exact on linear-Gaussian problems, the same linear
// system as Ceres' own evaluation (losses and manifolds included), the prior
// factor's Jacobian, and an unchanged optimum on a nonlinear window.
#include <memory>
#include <random>

#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/marginalization.h"
#include "rvlio/factors/plane_factor.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using test::RowMajorMatrix;

// f = sum_k A_k x_k - c.
class LinearCost final : public ceres::CostFunction {
 public:
  LinearCost(std::vector<MatrixXd> A, VectorXd c) : A_(std::move(A)), c_(std::move(c)) {
    set_num_residuals(static_cast<int>(c_.size()));
    for (const MatrixXd& a : A_) mutable_parameter_block_sizes()->push_back(a.cols());
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    VectorXd f = -c_;
    for (size_t k = 0; k < A_.size(); ++k) {
      f += A_[k] * Eigen::Map<const VectorXd>(x[k], A_[k].cols());
      if (jacobians && jacobians[k])
        Eigen::Map<RowMajorMatrix>(jacobians[k], A_[k].rows(), A_[k].cols()) = A_[k];
    }
    Eigen::Map<VectorXd>(residuals, f.size()) = f;
    return true;
  }

 private:
  std::vector<MatrixXd> A_;
  VectorXd c_;
};

MatrixXd RandomMatrix(std::mt19937& rng, int rows, int cols) {
  std::normal_distribution<double> n(0.0, 1.0);
  MatrixXd A(rows, cols);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = n(rng);
  return A;
}

// One Gauss-Newton step from the current values: exact for linear residuals
// on Euclidean blocks (no solver tolerances involved).
void SolveLinear(ceres::Problem* problem) {
  std::vector<double*> blocks;
  problem->GetParameterBlocks(&blocks);
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(problem->Evaluate(options, nullptr, &residuals, nullptr, &crs));
  MatrixXd J = MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) J(r, crs.cols[i]) = crs.values[i];
  const VectorXd f = Eigen::Map<const VectorXd>(residuals.data(), residuals.size());
  const VectorXd step = -J.colPivHouseholderQr().solve(f);
  int offset = 0;
  for (double* b : blocks) {
    const int size = problem->ParameterBlockSize(b);
    for (int i = 0; i < size; ++i) b[i] += step(offset + i);
    offset += size;
  }
}

ceres::Solver::Options TightOptions() {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = 50;
  o.function_tolerance = 1e-16;
  o.gradient_tolerance = 1e-16;
  o.parameter_tolerance = 1e-14;
  o.num_threads = 1;
  return o;
}

// A linear-Gaussian chain x0 - x1 - x2 - x3 (sizes 2, 3, 2, 1) with priors.
struct LinearProblem {
  std::vector<int> sizes = {2, 3, 2, 1};
  struct Res {
    std::vector<int> blocks;
    std::shared_ptr<LinearCost> cost;
  };
  std::vector<Res> residuals;

  explicit LinearProblem(std::mt19937& rng) {
    const std::vector<std::vector<int>> topology = {{0}, {0, 1}, {0, 2}, {1, 2},
                                                    {2, 3}, {3}, {1}, {1, 3}};
    for (const auto& blocks : topology) {
      int rows = 0;
      for (int b : blocks) rows += sizes[b];
      rows = std::max(1, rows - 1);
      std::vector<MatrixXd> A;
      for (int b : blocks) A.push_back(RandomMatrix(rng, rows, sizes[b]));
      residuals.push_back({blocks, std::make_shared<LinearCost>(A, RandomMatrix(rng, rows, 1))});
    }
  }
  // Adds the residuals touching none of `skip` (ceres does not own them).
  void AddTo(ceres::Problem* p, std::vector<std::vector<double>>& x, const std::vector<int>& skip) {
    for (const Res& r : residuals) {
      bool skipped = false;
      for (int b : r.blocks) skipped |= std::count(skip.begin(), skip.end(), b) > 0;
      if (skipped) continue;
      std::vector<double*> ptrs;
      for (int b : r.blocks) ptrs.push_back(x[b].data());
      p->AddResidualBlock(r.cost.get(), nullptr, ptrs);
    }
  }
};

ceres::Problem::Options NotOwning() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return o;
}

std::vector<std::vector<double>> RandomValues(std::mt19937& rng, const std::vector<int>& sizes) {
  std::vector<std::vector<double>> x;
  for (int s : sizes) {
    const MatrixXd v = RandomMatrix(rng, s, 1);
    x.emplace_back(v.data(), v.data() + s);
  }
  return x;
}

TEST(Marginalization, SchurPriorGivesTheFullSolutionOnLinearProblems) {
  std::mt19937 rng(41);
  for (int trial = 0; trial < 10; ++trial) {
    LinearProblem lp(rng);
    // Full solution.
    auto x_full = RandomValues(rng, lp.sizes);
    {
      ceres::Problem full(NotOwning());
      lp.AddTo(&full, x_full, {});
      SolveLinear(&full);
    }
    // Marginalize x0 at an arbitrary linearization point (exact for linear
    // residuals), then x1 together with the first prior.
    auto x = RandomValues(rng, lp.sizes);
    MarginalizationInfo info;
    for (const auto& r : lp.residuals) {
      if (r.blocks[0] != 0) continue;  // residuals touching x0 list it first
      std::vector<double*> ptrs;
      for (int b : r.blocks) ptrs.push_back(x[b].data());
      info.AddResidualBlock(r.cost.get(), nullptr, ptrs, {0});
    }
    ASSERT_TRUE(info.Marginalize().ok());
    auto prior1 = info.prior();
    EXPECT_EQ(prior1->blocks.size(), 2u);  // x1, x2
    EXPECT_EQ(prior1->tangent_dim, 5);
    EXPECT_EQ(prior1->rank, 5);
    MarginalizationFactor factor1(prior1);
    {
      ceres::Problem reduced(NotOwning());
      reduced.AddResidualBlock(&factor1, nullptr, prior1->blocks);
      lp.AddTo(&reduced, x, {0});
      SolveLinear(&reduced);
      for (int b = 1; b < 4; ++b)
        for (int i = 0; i < lp.sizes[b]; ++i) EXPECT_NEAR(x[b][i], x_full[b][i], 1e-9) << b;
    }
    // Second step from other values: drop x1 from {prior1, residuals on x1}.
    auto y = RandomValues(rng, lp.sizes);
    for (int b = 1; b < 4; ++b) x[b] = y[b];
    ceres::Problem step(NotOwning());
    step.AddResidualBlock(&factor1, nullptr, prior1->blocks);
    lp.AddTo(&step, x, {0});
    MarginalizationInfo info2;
    info2.AddFromProblem(step, {x[1].data()});
    ASSERT_TRUE(info2.Marginalize().ok());
    MarginalizationFactor factor2(info2.prior());
    ceres::Problem reduced2(NotOwning());
    reduced2.AddResidualBlock(&factor2, nullptr, info2.prior()->blocks);
    lp.AddTo(&reduced2, x, {0, 1});
    SolveLinear(&reduced2);
    for (int b = 2; b < 4; ++b)
      for (int i = 0; i < lp.sizes[b]; ++i) EXPECT_NEAR(x[b][i], x_full[b][i], 1e-9) << b;
  }
}

TEST(Marginalization, RejectsNothingToDropOrNothingToKeep) {
  std::mt19937 rng(42);
  LinearProblem lp(rng);
  auto x = RandomValues(rng, lp.sizes);
  MarginalizationInfo none;
  none.AddResidualBlock(lp.residuals[1].cost.get(), nullptr, {x[0].data(), x[1].data()}, {});
  EXPECT_EQ(none.Marginalize().code(), StatusCode::kInvalidInput);
  MarginalizationInfo all;
  all.AddResidualBlock(lp.residuals[0].cost.get(), nullptr, {x[0].data()}, {0});
  EXPECT_EQ(all.Marginalize().code(), StatusCode::kInvalidInput);
}

// A short window: poses with plane factors, IMU factors between states.
struct Window {
  static constexpr int kStates = 4;
  std::vector<std::vector<double>> pose, sb;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  PoseManifold manifold;
  ceres::HuberLoss huber{1.0};
  ceres::TolerantLoss tolerant{2.0, 1.0};

  explicit Window(std::mt19937& rng) {
    const Eigen::Vector3d bg(0.002, -0.001, 0.003), ba(0.03, -0.02, 0.01);
    ImuNoise noise;
    noise.gyro_noise_density = 1e-3;
    noise.accel_noise_density = 1e-2;
    noise.gyro_bias_random_walk = 1e-4;
    noise.accel_bias_random_walk = 1e-3;
    const TimeNs dt = 100000000, t0 = 200000000;
    const auto samples = test::SimulateImu(t0, t0 + kStates * dt, 5000000, bg, ba);
    for (int k = 0; k < kStates; ++k) {
      const TimeNs t = t0 + k * dt;
      pose.push_back(test::ToVector(test::TruePose(t)));
      sb.push_back(test::ToVector(test::TrueSpeedBias(t, bg, ba)));
      costs.emplace_back(new PlaneFactor(
          test::BoxRoomScan(rng, test::TruePose(t).ToPose3(), Pose3(), 60), Pose3(), 0.05));
      if (k + 1 < kStates)
        costs.emplace_back(new ImuFactor(
            ImuPreintegration::FromSamples(samples, t, t + dt, noise, Eigen::Vector3d::Zero(),
                                           Eigen::Vector3d::Zero()),
            test::Gravity()));
    }
  }
  // Residuals in a fixed order: plane 0, imu 0-1, plane 1, ...; optionally
  // skipping everything that touches state 0.
  void AddTo(ceres::Problem* p, bool skip_first, bool with_losses) {
    size_t c = 0;
    for (int k = 0; k < kStates; ++k) {
      ceres::CostFunction* plane = costs[c++].get();
      if (!(skip_first && k == 0))
        p->AddResidualBlock(plane, with_losses ? &huber : nullptr, pose[k].data());
      if (k + 1 == kStates) break;
      ceres::CostFunction* imu = costs[c++].get();
      if (!(skip_first && k == 0))
        p->AddResidualBlock(imu, with_losses ? &tolerant : nullptr,
                            {pose[k].data(), sb[k].data(), pose[k + 1].data(), sb[k + 1].data()});
    }
    for (int k = skip_first ? 1 : 0; k < kStates; ++k) p->SetManifold(pose[k].data(), &manifold);
  }
  void Perturb(std::mt19937& rng, int first) {
    for (int k = first; k < kStates; ++k) {
      Eigen::Matrix<double, 6, 1> d;
      d << test::RandomVector(rng, 0.02), test::RandomVector(rng, 0.1);
      Plus(PoseBlock::FromArray(pose[k].data()), d).ToArray(pose[k].data());  // in place
      for (int i = 0; i < 3; ++i) sb[k][i] += 0.05 * test::RandomVector(rng, 1.0)(i);
    }
  }
};

TEST(Marginalization, LinearSystemEqualsCeresEvaluationWithLossesAndManifolds) {
  std::mt19937 rng(43);
  Window w(rng);
  w.Perturb(rng, 0);  // away from the optimum: losses in their nonlinear regime
  ceres::Problem problem(NotOwning());
  w.AddTo(&problem, false, true);
  MarginalizationInfo info;
  info.AddFromProblem(problem, {w.pose[0].data(), w.sb[0].data()});
  ASSERT_TRUE(info.Marginalize().ok());
  EXPECT_EQ(info.dropped_dim(), 15);
  // Ceres' own Jacobian (tangent columns, corrector applied) over the same
  // residual blocks and columns.
  std::vector<ceres::ResidualBlockId> ids, touching;
  for (double* b : {w.pose[0].data(), w.sb[0].data()}) {
    problem.GetResidualBlocksForParameterBlock(b, &touching);
    for (auto id : touching)
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
  }
  ceres::Problem::EvaluateOptions eo;
  eo.parameter_blocks = info.ordered_blocks();
  eo.residual_blocks = ids;
  std::vector<double> residuals, gradient;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(problem.Evaluate(eo, nullptr, &residuals, &gradient, &crs));
  MatrixXd J = MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) J(r, crs.cols[i]) = crs.values[i];
  const MatrixXd H = J.transpose() * J;
  const VectorXd g = Eigen::Map<const VectorXd>(gradient.data(), gradient.size());
  ASSERT_EQ(H.rows(), info.H().rows());
  EXPECT_LT((H - info.H()).cwiseAbs().maxCoeff(), 1e-9 * H.cwiseAbs().maxCoeff());
  EXPECT_LT((g - info.b()).cwiseAbs().maxCoeff(), 1e-9 * g.cwiseAbs().maxCoeff());
}

TEST(Marginalization, PriorJacobianMatchesNumericThroughTheManifold) {
  std::mt19937 rng(44);
  Window w(rng);
  ceres::Problem problem(NotOwning());
  w.AddTo(&problem, false, false);
  MarginalizationInfo info;
  info.AddFromProblem(problem, {w.pose[0].data(), w.sb[0].data()});
  ASSERT_TRUE(info.Marginalize().ok());
  const MarginalizationFactor f(info.prior());
  ASSERT_EQ(f.prior().blocks.size(), 2u);  // pose 1, speed-bias 1
  std::vector<const ceres::Manifold*> manifolds = f.prior().manifolds;
  EXPECT_EQ(manifolds[0], &w.manifold);
  // At the linearization point the residual is r0 and J^T r = b*.
  for (int trial = 0; trial < 10; ++trial) {
    w.Perturb(rng, 1);  // far from x0: exercises JrInv(d_rot)
    EXPECT_LT(test::TangentJacobianError(f, {w.pose[1], w.sb[1]}, manifolds), 1e-7) << trial;
  }
}

TEST(Marginalization, NonlinearWindowKeepsItsOptimum) {
  // Solve the full window (first pose fixed), marginalize state 0 at the
  // optimum, re-solve the rest from a perturbed start with the prior: the
  // kept states return to the full solution.
  std::mt19937 rng(45);
  Window w(rng);
  w.Perturb(rng, 1);
  ceres::Problem full(NotOwning());
  w.AddTo(&full, false, true);
  full.SetParameterBlockConstant(w.pose[0].data());
  ceres::Solver::Summary s;
  ceres::Solve(TightOptions(), &full, &s);
  ASSERT_TRUE(s.IsSolutionUsable()) << s.BriefReport();
  const auto pose_opt = w.pose, sb_opt = w.sb;

  MarginalizationInfo info;
  info.AddFromProblem(full, {w.pose[0].data(), w.sb[0].data()});
  ASSERT_TRUE(info.Marginalize().ok());
  MarginalizationFactor prior(info.prior());
  w.Perturb(rng, 1);
  ceres::Problem reduced(NotOwning());
  reduced.AddResidualBlock(&prior, nullptr, info.prior()->blocks);
  w.AddTo(&reduced, true, true);
  ceres::Solve(TightOptions(), &reduced, &s);
  for (int k = 1; k < Window::kStates; ++k) {
    const auto d = Minus(PoseBlock::FromArray(w.pose[k].data()),
                         PoseBlock::FromArray(pose_opt[k].data()));
    EXPECT_LT(d.norm(), 1e-6) << k;
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(w.sb[k][i], sb_opt[k][i], 1e-5) << k << " " << i;
  }
}

}  // namespace
}  // namespace rvlio
