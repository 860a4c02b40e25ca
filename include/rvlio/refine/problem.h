#pragma once
// Batch refinement, steps 3 and 4: problem build and solve
// (refine/refine.h, "Solve"). One Ceres problem per chunk: PoseBlock +
// SpeedBiasBlock per scan, ImuFactor between consecutive scans (preintegrated
// at the current biases), each scan's plane factors from the association
// round (refine/association.h), the chunk's first pose held (gauge, or the
// previous chunk's result). Linear solver SPARSE_NORMAL_CHOLESKY with
// SuiteSparse CHOLMOD, Eigen's sparse Cholesky when Ceres lacks it. The
// IMU-only velocity and bias solve of the initialization uses the same
// pieces with every pose held.
#include <functional>
#include <string>
#include <vector>

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <ceres/types.h>
#include <Eigen/Core>

#include "rvlio/imu/noise.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/refine/association.h"
#include "rvlio/refine/chunks.h"
#include "rvlio/refine/init.h"
#include "rvlio/refine/states.h"

namespace rvlio {

// Problem options of every refine problem: the caller owns the one shared
// PoseManifold (it must outlive the problem).
ceres::Problem::Options RefineProblemOptions();

// The parameter blocks of the scans of `range`; hold_poses: poses constant.
void AddRefineStateBlocks(const ScanRange& range, bool hold_poses, PoseManifold* pose_manifold,
                          std::vector<RefineState>* states, ceres::Problem* problem);

// ImuFactor between consecutive scans of `range`, preintegrated over the
// sequence's IMU at the earlier scan's biases.
void AddRefineImuFactors(const RefineSequence& sequence, const ImuNoise& noise,
                         const Eigen::Vector3d& g_world, const ScanRange& range,
                         std::vector<RefineState>* states, ceres::Problem* problem);

// The chunk's problem: state blocks, each scan's plane factors (taken from
// *factors, one per scan of the chunk; the problem owns them), the IMU
// factors, and the chunk's first pose held unless hold_first_pose is false
// (the first chunk with a reference map: the reference fixes the gauge).
void BuildRefineChunkProblem(const RefineSequence& sequence, const ImuNoise& noise,
                             const Eigen::Vector3d& g_world, const ScanRange& chunk,
                             bool hold_first_pose, std::vector<ScanFactors>* factors,
                             PoseManifold* pose_manifold, std::vector<RefineState>* states,
                             ceres::Problem* problem);

// The degeneracy priors of the chunk's scans (ScanFactors::has_degeneracy_prior):
// a PosePriorFactor on pose k at anchors[k] (the scan's initial pose) with
// the scan's square-root information. Call after BuildRefineChunkProblem.
void AddRefineDegeneracyPriors(const ScanRange& chunk, const std::vector<ScanFactors>& factors,
                               const std::vector<PoseBlock>& anchors,
                               std::vector<RefineState>* states, ceres::Problem* problem);

// The linear solver the refine problems use, and the Ceres threads.
struct RefineSolver {
  ceres::SparseLinearAlgebraLibraryType sparse_library = ceres::EIGEN_SPARSE;
  int threads = 1;
  std::string name;  // RefineResult::linear_solver

  static RefineSolver Make(int threads);  // SuiteSparse when Ceres has it
  ceres::Solver::Options Options(int iterations) const;
};

struct RefineSolveReport {
  bool accepted = false;                       // false: the states of the range were restored
  double cost_before = 0.0, cost_after = 0.0;  // Ceres 1/2 |r|^2
  int iterations = 0;
  std::string message;  // Ceres' summary message
};

// Solves `problem`, whose variables are the states of `range`. A solution
// that is not usable, has non-finite states or a non-finite cost is rejected:
// the states of the range are restored from before the solve. stop (may be
// empty) is polled between iterations and aborts the solve.
RefineSolveReport SolveRefineProblem(ceres::Problem* problem, ceres::Solver::Options options,
                                     const ScanRange& range, const std::function<bool()>& stop,
                                     std::vector<RefineState>* states);

// Velocities and biases consistent with the IMU and the current poses: an
// IMU-only solve of all scans with every pose held (20 iterations).
RefineSolveReport SolveVelocityAndBias(const RefineSequence& sequence, const ImuNoise& noise,
                                       const Eigen::Vector3d& g_world, const RefineSolver& solver,
                                       std::vector<RefineState>* states);

}  // namespace rvlio
