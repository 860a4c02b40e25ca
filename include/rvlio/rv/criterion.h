#pragma once
// Vector-distribution criterion (paper Section 3.1 and 3.3, Alg. 1;
// docs/design.md "The RV pass").
//
// The constraint vectors u_i are the unit plane normals of one scan's
// point-to-plane constraints. Only their directions matter, so they share the
// origin and the "plane" alpha they may lie in passes through it (Eq. 16-18):
// its normal n_alpha is the last right singular vector of A = [u_1; ...; u_n]
// (Eq. 14), i.e. the eigenvector of the smallest eigenvalue of
// S = A^T A = sum_i u_i u_i^T (rows not centred). The coplanarity distance
// (Eq. 15) is taken in absolute value, d_i = |u_i . n_alpha|, because the sign
// of a plane normal is arbitrary. Special constraint vectors (SCVs): d_i > eps0.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/rv/options.h"

namespace rvlio {

// What the RV pass knows about one constraint vector.
enum class VectorClass : uint8_t {
  kUnusable = 0,  // zero-length or non-finite normal: ignored by RV and never edited
  kCoplanar = 1,  // d_i <= eps0 (in plane alpha)
  kScv = 2,       // special constraint vector, d_i > eps0
};

// Per-constraint scratch arrays of one RV pass. Reuse one object across scans
// to avoid reallocating (the vectors keep their capacity).
struct RvWorkspace {
  std::vector<Eigen::Vector3d> u;  // unit normals (zero when unusable)
  std::vector<double> d;           // d_i = |u_i . n_alpha| for the current plane (0 when unusable)
  std::vector<VectorClass> cls;
  int num_usable = 0;

  // Normalizes every constraint's normal into `u` (Alg. 1 step 1) and marks
  // the unusable ones; all usable vectors start as kCoplanar.
  void Load(const ConstraintList& constraints);
  int size() const { return static_cast<int>(u.size()); }
};

// Plane alpha through the origin fitted to a set of directions.
struct PlaneFit {
  Eigen::Vector3d n_alpha = Eigen::Vector3d::UnitZ();     // unit normal of alpha
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  // of S, ascending
};

// True for a finite normal with length > 1e-12 (the ones RV may use).
bool IsUsableNormal(const Eigen::Vector3d& u);

// Eq. (15) with the absolute value: d = |u . n_alpha| for unit u, n_alpha.
inline double CoplanarityDistance(const Eigen::Vector3d& u, const Eigen::Vector3d& n_alpha) {
  const double d = u.dot(n_alpha);
  return d < 0.0 ? -d : d;
}

// S = sum u_i u_i^T over the workspace vectors of class `which`.
Eigen::Matrix3d NormalScatter(const RvWorkspace& ws, VectorClass which);

// Eq. (14)-(16): n_alpha = eigenvector of the smallest eigenvalue of the
// symmetric S (self-adjoint solver). The sign is fixed so that the component of
// largest magnitude is positive (deterministic output). S = 0 gives UnitZ.
PlaneFit FitPlane(const Eigen::Matrix3d& S);

// Recomputes ws->d for every usable vector against n_alpha.
void ComputeDistances(const Eigen::Vector3d& n_alpha, RvWorkspace* ws);

struct CriterionResult {
  bool active = false;                          // Proposition 1 holds (see EvaluateCriterion)
  PlaneFit fit;                                 // Alg. 1 plane on all usable vectors
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();  // sum u_i u_i^T over usable vectors
  int num_usable = 0;
  int num_within_eps0 = 0;         // d_i <= eps0
  double coplanar_fraction = 0.0;  // num_within_eps0 / num_usable (0 when none)
};

// Alg. 1 on the normals of `constraints`. Fills ws (unit normals, d_i, and the
// class kScv for d_i > eps0). Activation (our reading of "most vectors" in
// Proposition 1, docs/design.md "The RV pass"): num_usable >= min_constraints and the
// fraction of usable vectors with d_i <= eps0 is >= activation_ratio.
CriterionResult EvaluateCriterion(const RvOptions& options, const ConstraintList& constraints,
                                  RvWorkspace* ws);

}  // namespace rvlio
