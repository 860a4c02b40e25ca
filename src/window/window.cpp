#include "rvlio/window/window.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Eigenvalues>
#include <ceres/normal_prior.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include "rvlio/common/check.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/constraints/robust_kernel.h"
#include "rvlio/factors/imu_factor.h"
#include "rvlio/factors/plane_time_offset_factor.h"
#include "rvlio/factors/pose_projected_factor.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/math/so3.h"
#include "scan_factor.h"

namespace rvlio {

struct SlidingWindow::Node {
  TimeNs t_ns = 0;
  double pose[PoseBlock::kNumParams] = {0, 0, 0, 1, 0, 0, 0};
  double sb[SpeedBiasBlock::kNumParams] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
  std::vector<Eigen::Vector3d> p_lidar;
  ConstraintList constraints;  // of the last association, RV and Huber weights applied
  RvReport rv;
  Pose3 associated_at;  // T_world_imu of the last association
  bool associated = false;
  // The scan's plane factor, of the window's ScanFactorKind (scan_factor.h);
  // null: too few constraints, or its summary overflowed.
  std::unique_ptr<ceres::CostFunction> plane;
  ScanTimeMotion motion;   // held at t_ns (estimate_time_offset)
  double td_lin_s = 0.0;   // the time offset the scan was deskewed with
  std::unique_ptr<ImuFactor> imu;                    // from the previous node, or null
  std::unique_ptr<SpeedBiasContinuityFactor> gap;    // from the previous node when imu is null
  PoseBlock anchor;  // the initial value (IMU prediction): where a degeneracy prior holds the pose
  DegeneracyReport degeneracy;                          // of the last association
  std::unique_ptr<PosePriorFactor> degeneracy_prior;   // null: no weak direction treated
  // remap (project form): the plane factor without its say along the held
  // directions; null otherwise. degeneracy_prior then holds the hold form,
  // used while the pose is tied to no other state (ScanCost).
  std::unique_ptr<PoseProjectedFactor> plane_remapped;

  // The cost of the plane factor in a solve or a marginalization.
  // tied: an IMU factor or a prior also ties the pose, so the projected form
  // leaves no direction free; untied (IMU gaps on both sides), the remapped
  // directions are held at the anchor instead.
  ceres::CostFunction* ScanCost(bool tied) const {
    return plane_remapped && tied ? plane_remapped.get() : plane.get();
  }
  PosePriorFactor* DegeneracyPrior(bool tied) const {
    return plane_remapped && tied ? nullptr : degeneracy_prior.get();
  }

  Pose3 T_world_imu() const { return PoseBlock::FromArray(pose).ToPose3(); }
  // The pose the scan's factor sees: a remapped factor is blind along its
  // held directions, so moving there does not make its constraints stale.
  Pose3 SeenPose(bool tied) const {
    if (!plane_remapped || !tied) return T_world_imu();
    return plane_remapped->Projected(PoseBlock::FromArray(pose)).ToPose3();
  }
};

namespace {

constexpr int kBlockSize = PoseBlock::kNumParams + SpeedBiasBlock::kNumParams;
// Lever arm that turns a rotation into a point displacement for the
// re-association test: a point 10 m away moves by about 10 m x angle.
constexpr double kReassociationLeverArm = 10.0;  // m
// Weak continuity across an IMU gap (SpeedBiasContinuityFactor): loose
// enough not to fight the LiDAR, tight enough to keep the speed and biases
// of a state without an IMU factor observable.
constexpr double kGapVelStd = 1.0;  // m/s
constexpr double kGapBgStd = 1e-3;  // rad/s
constexpr double kGapBaStd = 1e-2;  // m/s^2
// A preintegration is integrated again when the bias estimate moved this far
// from its linearization biases (the first-order bias correction degrades).
constexpr double kRepropagateBg = 2e-3;  // rad/s
constexpr double kRepropagateBa = 2e-2;  // m/s^2
// A solution with a speed above this is treated as diverged (a multirotor or
// a car stays far below; the divergence monitor's own limit is configurable).
constexpr double kMaxSpeed = 100.0;  // m/s

// The first state's prior: the filter's initial standard deviations (both
// backends start from the same static initialization).
StatePriorStd FirstPriorStd(const IeskfOptions& o) {
  StatePriorStd s;
  s.rot = o.init_rot_std;
  s.pos = o.init_pos_std;
  s.vel = o.init_vel_std;
  s.bg = o.init_bias_gyro_std;
  s.ba = o.init_bias_acc_std;
  return s;
}

ceres::Problem::Options ProblemOptions() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  o.enable_fast_removal = false;
  return o;
}

bool IsFinite(const ImuPreintegration& p) {
  return p.dR().allFinite() && p.dv().allFinite() && p.dp().allFinite() &&
         p.covariance().allFinite() && p.bias_jacobian().allFinite();
}

// Translation plus lever arm times rotation angle between two poses (m).
double Motion(const Pose3& a, const Pose3& b) {
  return (a.t - b.t).norm() + kReassociationLeverArm * so3::Log(a.R.transpose() * b.R).norm();
}

void RemoveNonFinite(ConstraintList* constraints) {
  constraints->erase(std::remove_if(constraints->begin(), constraints->end(),
                                    [](const Constraint& c) {
                                      return !c.p_lidar.allFinite() || !c.normal_world.allFinite() ||
                                             !c.q_world.allFinite() || !std::isfinite(c.weight);
                                    }),
                     constraints->end());
}

// |r| at the current pose, with the possibly repaired normal: where the
// Huber weight (constraints/robust_kernel.h) is taken.
void RefreshResiduals(const Pose3& T_world_imu, const Pose3& T_imu_lidar,
                      ConstraintList* constraints) {
  for (Constraint& c : *constraints)
    c.residual = std::abs(PointToPlaneResidual(c, T_world_imu, T_imu_lidar));
}

}  // namespace

ceres::LinearSolverType WindowLinearSolver(const std::string& name) {
  if (name == "dense_normal_cholesky") return ceres::DENSE_NORMAL_CHOLESKY;
  if (name == "sparse_normal_cholesky") return ceres::SPARSE_NORMAL_CHOLESKY;
  if (name == "dense_qr") return ceres::DENSE_QR;
  RVLIO_CHECK_MSG(name == "dense_schur", "unknown smoother.linear_solver");
  return ceres::DENSE_SCHUR;
}

SlidingWindow::SlidingWindow(const WindowOptions& options)
    : options_(options),
      T_imu_lidar_config_(ImuTLidar(options.extrinsics)),
      first_prior_(FirstPriorStd(options.ieskf)),
      scan_factor_kind_(MakeScanFactorKind(options.smoother.estimate_extrinsics,
                                           options.lidar.estimate_time_offset)) {
  RVLIO_CHECK(options_.smoother.window_size >= 2);
  RVLIO_CHECK(options_.constraints.lidar_noise > 0.0 &&
              options_.smoother.sliding_window_huber_delta > 0.0);
  PoseBlock(T_imu_lidar_config_.quaternion(), T_imu_lidar_config_.t).ToArray(extrinsic_);
  Vector6d prior_std;
  prior_std << Eigen::Vector3d::Constant(options_.smoother.extrinsic_rot_std),
      Eigen::Vector3d::Constant(options_.smoother.extrinsic_pos_std);
  excitation_ = ExtrinsicExcitation(prior_std);
  time_offset_[0] = options_.lidar.time_offset;
  RVLIO_CHECK_MSG(!(estimate_time_offset() && estimate_extrinsics()),
                  "the smoother estimates the extrinsic or the time offset, not both");
}

namespace {

// A 1-d Gaussian prior on the time offset at td_s.
std::unique_ptr<ceres::CostFunction> TimeOffsetPrior(double td_s, double std_s) {
  ceres::Matrix A(1, 1);
  A(0, 0) = 1.0 / std_s;
  ceres::Vector b(1);
  b(0) = td_s;
  return std::make_unique<ceres::NormalPrior>(A, b);
}

}  // namespace

Pose3 SlidingWindow::ScanPose(const Node& node) const {
  return scan_factor_kind_->ScanPose(
      {node.T_world_imu(), node.sb, node.motion, time_offset_[0] - node.td_lin_s});
}

Pose3 SlidingWindow::ScanTimeImuPose(int k) const {
  RVLIO_CHECK(k >= 0 && k < size());
  return ScanPose(*nodes_[k]);
}

// An estimate past +-lidar.time_offset_max is held at the bound (reported).
void SlidingWindow::HoldTimeOffsetInBound() {
  if (!estimate_time_offset() || std::abs(time_offset_[0]) <= options_.lidar.time_offset_max)
    return;
  time_offset_[0] = std::copysign(options_.lidar.time_offset_max, time_offset_[0]);
}

Pose3 SlidingWindow::T_imu_lidar() const {
  return estimate_extrinsics() ? PoseBlock::FromArray(extrinsic_).ToPose3() : T_imu_lidar_config_;
}

SlidingWindow::~SlidingWindow() = default;

std::unique_ptr<SlidingWindow::Node> SlidingWindow::MakeNode(
    TimeNs t_ns, const PoseBlock& pose, const SpeedBiasBlock& speed_bias,
    std::vector<Eigen::Vector3d> p_lidar) {
  auto node = std::make_unique<Node>();
  node->t_ns = t_ns;
  pose.ToArray(node->pose);
  node->anchor = pose;
  speed_bias.ToArray(node->sb);
  node->p_lidar = std::move(p_lidar);
  return node;
}

// The priors of the estimated calibration (extrinsic, time offset) at their
// current values with their initial standard deviations: at the start, and
// again when a failed marginalization dropped the information they held.
void SlidingWindow::ResetCalibrationPriors() {
  if (estimate_extrinsics())
    extrinsic_prior_ = std::make_unique<PosePriorFactor>(
        PoseBlock::FromArray(extrinsic_), options_.smoother.extrinsic_rot_std,
        options_.smoother.extrinsic_pos_std);
  if (estimate_time_offset()) {
    time_offset_prior_ = TimeOffsetPrior(time_offset_[0], options_.lidar.time_offset_init_std);
    time_offset_std_s_ = options_.lidar.time_offset_init_std;
  }
}

void SlidingWindow::Start(TimeNs t_ns, const PoseBlock& pose, const SpeedBiasBlock& speed_bias,
                          std::vector<Eigen::Vector3d> p_lidar) {
  nodes_.clear();
  marginal_prior_.reset();
  state_prior_ = std::make_unique<StatePriorFactor>(pose, speed_bias, first_prior_);
  ResetCalibrationPriors();
  nodes_.push_back(MakeNode(t_ns, pose, speed_bias, std::move(p_lidar)));
  nodes_.back()->td_lin_s = time_offset_[0];
}

void SlidingWindow::Add(TimeNs t_ns, const PoseBlock& pose, const SpeedBiasBlock& speed_bias,
                        std::optional<ImuPreintegration> imu,
                        std::vector<Eigen::Vector3d> p_lidar, const ScanTimeMotion& motion) {
  RVLIO_CHECK_MSG(!nodes_.empty(), "SlidingWindow::Start() first");
  RVLIO_CHECK_MSG(t_ns >= nodes_.back()->t_ns, "window states must be added in time order");
  std::unique_ptr<Node> node = MakeNode(t_ns, pose, speed_bias, std::move(p_lidar));
  node->motion = motion;
  node->td_lin_s = time_offset_[0];
  if (imu && imu->dt() > 0.0 && IsFinite(*imu)) {
    node->imu = std::make_unique<ImuFactor>(std::move(*imu), options_.g_world);
  } else {
    ++stats_.imu_factors_skipped;
    node->gap = std::make_unique<SpeedBiasContinuityFactor>(
        kGapVelStd, kGapBgStd, kGapBaStd);
  }
  nodes_.push_back(std::move(node));
}

WindowState SlidingWindow::state(int k) const {
  RVLIO_CHECK(k >= 0 && k < size());
  const Node& n = *nodes_[k];
  return {n.t_ns, PoseBlock::FromArray(n.pose), SpeedBiasBlock::FromArray(n.sb)};
}

const std::vector<Eigen::Vector3d>& SlidingWindow::points(int k) const {
  RVLIO_CHECK(k >= 0 && k < size());
  return nodes_[k]->p_lidar;
}

const ConstraintList& SlidingWindow::constraints(int k) const {
  RVLIO_CHECK(k >= 0 && k < size());
  return nodes_[k]->constraints;
}

bool SlidingWindow::has_imu_factor(int k) const {
  RVLIO_CHECK(k >= 0 && k < size());
  return nodes_[k]->imu != nullptr;
}

WindowSolveReport SlidingWindow::Optimize(const ScanAssociateFn& associate) {
  WindowSolveReport report;
  if (nodes_.empty()) return report;
  bool retried = false;
  for (int round = 0; round < options_.smoother.association_rounds; ++round) {
    const double t0 = ThreadCpuMs();
    const int associated = AssociateRound(associate, &report);
    const double t1 = ThreadCpuMs();
    report.association_ms += t1 - t0;
    // A later round whose association changed nothing would solve the
    // problem the previous round has just solved (and so would every round
    // after it).
    if (round > 0 && associated == 0 && !options_.smoother.solve_unchanged_rounds) break;
    const bool ok = SolveRound(&report);
    report.solve_ms += ThreadCpuMs() - t1;
    if (ok) {
      ++report.rounds;
      continue;
    }
    ++report.failures;
    // The newest IMU interval is the likeliest culprit (a corrupt burst of
    // samples): redo the round once without it, else give up on this scan.
    if (retried || !DropNewestImuFactor()) {
      report.ok = false;
      break;
    }
    retried = true;
    report.dropped_newest_imu = true;
    --round;
  }
  report.newest_constraints = static_cast<int>(nodes_.back()->constraints.size());
  report.newest_rv = nodes_.back()->rv;
  report.newest_degeneracy = nodes_.back()->degeneracy;
  report.newest_position_information = PositionInformation(nodes_.back()->constraints);
  return report;
}

bool SlidingWindow::DropNewestImuFactor() {
  Node& n = *nodes_.back();
  if (nodes_.size() < 2 || !n.imu) return false;
  n.imu.reset();
  n.gap = std::make_unique<SpeedBiasContinuityFactor>(kGapVelStd, kGapBgStd, kGapBaStd);
  ++stats_.imu_factors_skipped;
  return true;
}

// Every state never associated, or moved by more than reassociate_min_motion
// since its last association (its constraints would be stale).
// Returns how many were (re-)associated.
int SlidingWindow::AssociateRound(const ScanAssociateFn& associate, WindowSolveReport* report) {
  int associated = 0;
  for (size_t k = 0; k < nodes_.size(); ++k) {
    Node* node = nodes_[k].get();
    if (node->associated && Motion(node->associated_at, node->SeenPose(PoseTied(k))) <=
                                options_.smoother.reassociate_min_motion)
      continue;
    AssociateNode(associate, node);
    ++associated;
  }
  report->associations += associated;
  return associated;
}

// Associate -> RV (Alg. 1-3 on this scan's list) -> the degeneracy method's
// analysis -> Huber weights -> factor -> the method's treatment of it.
void SlidingWindow::AssociateNode(const ScanAssociateFn& associate, Node* node) {
  const Pose3 T_world_imu = ScanPose(*node);  // the state's pose unless estimate_time_offset
  const Pose3 T_imu_lidar = this->T_imu_lidar();
  associate(node->p_lidar, T_world_imu, &node->constraints);
  RemoveNonFinite(&node->constraints);
  node->rv = ApplyRv(options_.rv, T_world_imu * T_imu_lidar, &node->constraints, &rv_workspace_);
  RefreshResiduals(T_world_imu, T_imu_lidar, &node->constraints);
  const LeastSquaresDegeneracy degeneracy = AnalyzeNodeDegeneracy(T_world_imu, T_imu_lidar, *node);
  ApplyHuberWeights(options_.smoother.sliding_window_huber_delta, &node->constraints);
  node->associated_at = node->T_world_imu();
  node->associated = true;
  node->plane.reset();
  ClearDegeneracy(node);
  if (static_cast<int>(node->constraints.size()) < kMinPoseConstraints) return;
  node->plane = scan_factor_kind_->Make({node->constraints, options_.constraints.lidar_noise,
                                         T_imu_lidar_config_, node->motion, node->td_lin_s,
                                         T_world_imu.t});
  if (!node->plane) {
    RejectOverflowingScan(node);
    return;
  }
  TreatDegeneracy(degeneracy, node);
}

// remap, localizability, regularized: the scan's pose information at the
// pose of this association, with the weights before the robust kernel (the
// geometry, not how well the prediction fits it; RV is off for these
// methods) -> the method's weak directions and prior
// (TreatLeastSquaresDegeneracy, shared with refine).
LeastSquaresDegeneracy SlidingWindow::AnalyzeNodeDegeneracy(const Pose3& T_world_imu,
                                                            const Pose3& T_imu_lidar,
                                                            const Node& node) const {
  if (static_cast<int>(node.constraints.size()) < kMinPoseConstraints) {
    LeastSquaresDegeneracy none;
    none.report.method = options_.degeneracy.method;
    return none;
  }
  return TreatLeastSquaresDegeneracy(options_.degeneracy, node.constraints, T_world_imu,
                                     T_imu_lidar, options_.constraints.lidar_noise);
}

// remap (degeneracy.remap_window_form project): the scan's plane factor
// loses its say along the held directions (PoseProjectedFactor at the
// association pose); the window's other factors place the pose there.
// Otherwise (localizability, regularized, remap in the hold form): a prior
// at the node's anchor along the held or damped directions (sigma: the plane
// factor's lidar_noise, so the prior is in the scan's units).
void SlidingWindow::TreatDegeneracy(const LeastSquaresDegeneracy& d, Node* node) const {
  node->degeneracy = d.report;
  if (options_.degeneracy.method == DegeneracyMethod::kRemap &&
      options_.degeneracy.remap_window_form == RemapWindowForm::kProject && d.num_held > 0)
    node->plane_remapped = std::make_unique<PoseProjectedFactor>(
        node->plane.get(), PoseBlock(node->associated_at), d.held_pose.leftCols(d.num_held));
  if (d.has_prior)
    node->degeneracy_prior = std::make_unique<PosePriorFactor>(node->anchor, d.sqrt_information);
}

void SlidingWindow::ClearDegeneracy(Node* node) const {
  node->plane_remapped.reset();
  node->degeneracy_prior.reset();
  node->degeneracy = DegeneracyReport();
  node->degeneracy.method = options_.degeneracy.method;
}

// Finite but absurd records (a plane 1e300 m away) overflow the summary:
// such a scan contributes nothing (and is associated again next round)
// rather than a cost Ceres cannot evaluate.
void SlidingWindow::RejectOverflowingScan(Node* node) {
  ClearDegeneracy(node);
  node->plane.reset();
  node->constraints.clear();
  node->associated = false;
  ++stats_.rejected_scans;
}

// Re-integrates a preintegration whose linearization biases are far from the
// current estimate of the earlier state (first-order correction no longer
// accurate).
void SlidingWindow::RefreshImuFactors() {
  for (size_t k = 1; k < nodes_.size(); ++k) {
    Node& n = *nodes_[k];
    if (!n.imu) continue;
    const SpeedBiasBlock sb = SpeedBiasBlock::FromArray(nodes_[k - 1]->sb);
    const ImuPreintegration& pre = n.imu->preintegration();
    if ((sb.bg - pre.bg_lin()).norm() <= kRepropagateBg &&
        (sb.ba - pre.ba_lin()).norm() <= kRepropagateBa)
      continue;
    ImuPreintegration again = pre;
    again.Repropagate(sb.bg, sb.ba);
    if (!IsFinite(again)) continue;
    n.imu = std::make_unique<ImuFactor>(std::move(again), options_.g_world);
    ++stats_.repropagations;
  }
}

// Whether a factor besides its scan's ties state k's pose: an IMU factor
// from or to a neighbour, or (the oldest state) the start or marginal prior.
bool SlidingWindow::PoseTied(size_t k) const {
  if (k > 0 && nodes_[k]->imu) return true;
  if (k + 1 < nodes_.size() && nodes_[k + 1]->imu) return true;
  if (k > 0) return false;
  if (state_prior_) return true;
  if (!marginal_prior_) return false;
  const std::vector<double*>& blocks = marginal_prior_->prior().blocks;
  return std::find(blocks.begin(), blocks.end(), nodes_[0]->pose) != blocks.end();
}

// The parameter blocks of a node's scan factor (ScanFactorKind::Blocks);
// time_offset: the window's, or in a marginalization the leaving scan's.
std::vector<double*> SlidingWindow::ScanBlocks(Node* node, double* time_offset) {
  return scan_factor_kind_->Blocks({node->pose, node->sb, extrinsic_, time_offset});
}

bool SlidingWindow::SolveRound(WindowSolveReport* report) {
  RefreshImuFactors();
  Backup();
  ceres::Problem problem(ProblemOptions());
  std::vector<bool> pose_used(nodes_.size(), false);
  if (estimate_extrinsics()) AddExtrinsicBlock(&problem);
  for (size_t k = 0; k < nodes_.size(); ++k) {
    Node& n = *nodes_[k];
    const bool tied = PoseTied(k);
    problem.AddParameterBlock(n.pose, PoseBlock::kNumParams, &pose_manifold_);
    problem.AddParameterBlock(n.sb, SpeedBiasBlock::kNumParams);
    if (n.plane) {
      problem.AddResidualBlock(n.ScanCost(tied), nullptr, ScanBlocks(&n, time_offset_));
      pose_used[k] = true;
    }
    if (PosePriorFactor* prior = n.DegeneracyPrior(tied))
      problem.AddResidualBlock(prior, nullptr, n.pose);
    if (k == 0) continue;
    Node& p = *nodes_[k - 1];
    if (n.imu) {
      problem.AddResidualBlock(n.imu.get(), nullptr, p.pose, p.sb, n.pose, n.sb);
      pose_used[k] = pose_used[k - 1] = true;
    } else {
      problem.AddResidualBlock(n.gap.get(), nullptr, p.sb, n.sb);
    }
  }
  Node& first = *nodes_.front();
  if (state_prior_) {
    problem.AddResidualBlock(state_prior_.get(), nullptr, first.pose, first.sb);
    pose_used[0] = true;
  }
  if (marginal_prior_) {
    const std::vector<double*>& blocks = marginal_prior_->prior().blocks;
    problem.AddResidualBlock(marginal_prior_.get(), nullptr, blocks);
    if (std::find(blocks.begin(), blocks.end(), first.pose) != blocks.end()) pose_used[0] = true;
  }
  if (extrinsic_prior_) problem.AddResidualBlock(extrinsic_prior_.get(), nullptr, extrinsic_);
  if (time_offset_prior_)
    problem.AddResidualBlock(time_offset_prior_.get(), nullptr, time_offset_);
  // A pose no factor touches (IMU gap and no scan constraints) keeps its
  // prediction.
  for (size_t k = 0; k < nodes_.size(); ++k)
    if (!pose_used[k]) problem.SetParameterBlockConstant(nodes_[k]->pose);

  ceres::Solver::Options so;
  so.linear_solver_type = WindowLinearSolver(options_.smoother.linear_solver);
  so.max_num_iterations = options_.smoother.max_solver_iterations;
  so.function_tolerance = options_.smoother.function_tolerance;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  report->iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
  if (summary.IsSolutionUsable() && Healthy()) {
    HoldTimeOffsetInBound();
    return true;
  }
  Restore();
  ++stats_.solve_failures;
  // This round's associations may be what broke the solve, and the restored
  // poses equal the poses they were made at: re-associate everything next.
  for (auto& node : nodes_) node->associated = false;
  return false;
}

// The extrinsic block: axes not yet excited held fixed (see window.h).
void SlidingWindow::AddExtrinsicBlock(ceres::Problem* problem) {
  problem->AddParameterBlock(extrinsic_, PoseBlock::kNumParams);
  std::array<bool, 6> free;
  int num_free = 0;
  for (int i = 0; i < 6; ++i) num_free += (free[i] = excitation_.excited(i)) ? 1 : 0;
  if (num_free == 0) {
    problem->SetParameterBlockConstant(extrinsic_);
  } else if (num_free == 6) {
    problem->SetManifold(extrinsic_, &pose_manifold_);
  } else {
    extrinsic_manifold_ = std::make_unique<PoseSubsetManifold>(free);
    problem->SetManifold(extrinsic_, extrinsic_manifold_.get());
  }
}

bool SlidingWindow::Healthy() const {
  const Eigen::Map<const Eigen::Matrix<double, 7, 1>> extrinsic(extrinsic_);
  if (!extrinsic.allFinite() || std::abs(extrinsic.head<4>().norm() - 1.0) > 1e-3) return false;
  if (!std::isfinite(time_offset_[0])) return false;
  for (const auto& n : nodes_) {
    const Eigen::Map<const Eigen::Matrix<double, 7, 1>> pose(n->pose);
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> sb(n->sb);
    if (!pose.allFinite() || !sb.allFinite()) return false;
    if (std::abs(pose.head<4>().norm() - 1.0) > 1e-3) return false;
    if (sb.head<3>().norm() > kMaxSpeed) return false;
  }
  return true;
}

void SlidingWindow::Backup() {
  backup_.resize(nodes_.size() * kBlockSize + PoseBlock::kNumParams + 1);
  double* out = std::copy(extrinsic_, extrinsic_ + PoseBlock::kNumParams, backup_.data());
  *out++ = time_offset_[0];
  for (const auto& n : nodes_) {
    out = std::copy(n->pose, n->pose + PoseBlock::kNumParams, out);
    out = std::copy(n->sb, n->sb + SpeedBiasBlock::kNumParams, out);
  }
}

void SlidingWindow::Restore() {
  RVLIO_CHECK(backup_.size() == nodes_.size() * kBlockSize + PoseBlock::kNumParams + 1);
  const double* in = backup_.data();
  std::copy(in, in + PoseBlock::kNumParams, extrinsic_);
  in += PoseBlock::kNumParams;
  time_offset_[0] = *in++;
  for (auto& n : nodes_) {
    std::copy(in, in + PoseBlock::kNumParams, n->pose);
    in += PoseBlock::kNumParams;
    std::copy(in, in + SpeedBiasBlock::kNumParams, n->sb);
    in += SpeedBiasBlock::kNumParams;
  }
}

// Schur complement of the oldest state over every factor that touches it:
// the previous prior, its plane factor and the IMU (or continuity) factor to
// the next state. The new prior is linearized here, at the final estimate of
// the oldest state, and keeps that linearization point (marginalization.h).
std::optional<MarginalizedScan> SlidingWindow::MarginalizeIfFull() {
  if (size() < options_.smoother.window_size || size() < 2) return std::nullopt;
  Node& old = *nodes_[0];
  Node& next = *nodes_[1];
  const bool old_tied = PoseTied(0);
  MarginalizationInfo info;
  info.SetManifold(old.pose, &pose_manifold_);
  info.SetManifold(next.pose, &pose_manifold_);
  if (estimate_extrinsics()) info.SetManifold(extrinsic_, &pose_manifold_);
  // lidar.time_offset_random_walk: the offset of the leaving scan and of the
  // information before it (td_prev, dropped with the scan) is tied to the
  // window's offset by a random walk over the interval to the next scan, so
  // the prior carries the offset with its variance grown by q^2 dt. Without
  // it (q = 0) one offset for the whole recording.
  const double walk_dt_s = NsToSeconds(next.t_ns - old.t_ns);
  const bool walk = estimate_time_offset() && options_.lidar.time_offset_random_walk > 0.0 &&
                    walk_dt_s > 0.0;
  double td_prev[1] = {time_offset_[0]};
  double* const td_old = walk ? td_prev : time_offset_;
  const auto dropped = [&old, td_prev_ptr = walk ? td_prev : nullptr](
                           const std::vector<double*>& blocks) {
    std::vector<int> indices;
    for (size_t i = 0; i < blocks.size(); ++i)
      if (blocks[i] == old.pose || blocks[i] == old.sb || blocks[i] == td_prev_ptr)
        indices.push_back(static_cast<int>(i));
    return indices;
  };
  if (marginal_prior_) {
    std::vector<double*> blocks = marginal_prior_->prior().blocks;
    std::replace(blocks.begin(), blocks.end(), static_cast<double*>(time_offset_), td_old);
    info.AddResidualBlock(marginal_prior_.get(), nullptr, blocks, dropped(blocks));
  }
  if (state_prior_) info.AddResidualBlock(state_prior_.get(), nullptr, {old.pose, old.sb}, {0, 1});
  if (old.plane) {
    const std::vector<double*> blocks = ScanBlocks(&old, td_old);
    info.AddResidualBlock(old.ScanCost(old_tied), nullptr, blocks, dropped(blocks));
  }
  if (extrinsic_prior_) info.AddResidualBlock(extrinsic_prior_.get(), nullptr, {extrinsic_}, {});
  if (time_offset_prior_)
    info.AddResidualBlock(time_offset_prior_.get(), nullptr, {td_old}, dropped({td_old}));
  std::unique_ptr<TimeOffsetRandomWalkFactor> td_walk;
  if (walk) {
    td_walk = std::make_unique<TimeOffsetRandomWalkFactor>(options_.lidar.time_offset_random_walk,
                                                           walk_dt_s);
    info.AddResidualBlock(td_walk.get(), nullptr, {td_prev, time_offset_}, {0});
  }
  if (next.imu)
    info.AddResidualBlock(next.imu.get(), nullptr, {old.pose, old.sb, next.pose, next.sb}, {0, 1});
  else
    info.AddResidualBlock(next.gap.get(), nullptr, {old.sb, next.sb}, {0});
  const Status status = info.Marginalize();

  MarginalizedScan out{state(0), ScanPose(old), std::move(old.p_lidar)};
  state_prior_.reset();
  marginal_prior_.reset();
  if (status.ok() && info.prior()->rank > 0) {
    marginal_prior_ = std::make_unique<MarginalizationFactor>(info.prior());
    extrinsic_prior_.reset();  // now inside the marginalization prior
    time_offset_prior_.reset();
    if (estimate_extrinsics()) ObserveExtrinsicExcitation();
    if (estimate_time_offset()) ObserveTimeOffsetStd();
  } else {
    // Keep the window anchored: a prior at the next state's estimate.
    ++stats_.marginalization_failures;
    state_prior_ = std::make_unique<StatePriorFactor>(PoseBlock::FromArray(next.pose),
                                                      SpeedBiasBlock::FromArray(next.sb),
                                                      first_prior_);
    // The calibration's information went with the failed prior: its priors again.
    ResetCalibrationPriors();
  }
  ++stats_.marginalizations;
  next.imu.reset();
  next.gap.reset();
  nodes_.pop_front();
  return out;
}

void SlidingWindow::CountExcitationScan() {
  if (nodes_.empty()) return;
  const Node& newest = *nodes_.back();
  excitation_.CountScan(newest.t_ns, newest.T_world_imu().R, T_imu_lidar().R);
}

namespace {

// Marginal covariance of the `size` tangent entries of `block` under the
// marginalization prior (H* = S^T S over the kept blocks; pseudo-inverse with
// the marginalization's relative eigenvalue floor); an entry with no
// information (zero eigenvalue) gets an infinite variance, not zero. False
// when the block is not in the prior or the decomposition fails.
bool PriorMarginalCovariance(const MarginalizationPrior& prior, const double* block, int size,
                             Eigen::MatrixXd* C_block) {
  const auto it = std::find(prior.blocks.begin(), prior.blocks.end(), block);
  if (it == prior.blocks.end()) return false;
  const int offset = prior.tangent_offsets[it - prior.blocks.begin()];
  const Eigen::MatrixXd H = prior.S.transpose() * prior.S;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H);
  if (eig.info() != Eigen::Success) return false;
  const double floor = 1e-12 * std::max(eig.eigenvalues().maxCoeff(), 0.0);
  const Eigen::VectorXd inv = eig.eigenvalues().unaryExpr(
      [floor](double l) { return l > floor ? 1.0 / l : 0.0; });
  const Eigen::MatrixXd C = eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
  *C_block = C.block(offset, offset, size, size);
  const Eigen::MatrixXd V = eig.eigenvectors().middleRows(offset, size);
  for (int k = 0; k < eig.eigenvalues().size(); ++k)
    if (eig.eigenvalues()(k) <= floor)
      for (int i = 0; i < size; ++i)
        if (std::abs(V(i, k)) > 1e-6) (*C_block)(i, i) = std::numeric_limits<double>::infinity();
  return true;
}

}  // namespace

// The marginal 1-sigma of the time offset under the marginalization prior.
void SlidingWindow::ObserveTimeOffsetStd() {
  Eigen::MatrixXd C;
  if (PriorMarginalCovariance(marginal_prior_->prior(), time_offset_, 1, &C))
    time_offset_std_s_ = std::sqrt(C(0, 0));
}

// The marginal covariance of the extrinsic block under the marginalization
// prior: the information of every scan that left the window, judged as if all
// six axes were estimated.
void SlidingWindow::ObserveExtrinsicExcitation() {
  Eigen::MatrixXd C;
  if (PriorMarginalCovariance(marginal_prior_->prior(), extrinsic_, 6, &C))
    excitation_.Observe(Matrix6d(C));
}

}  // namespace rvlio
