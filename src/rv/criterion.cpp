#include "rvlio/rv/criterion.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"

namespace rvlio {

namespace {

// Upper triangle of a running sum of w u u^T (cheaper than 3x3 outer products).
struct SymmetricSum {
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  void Add(const Eigen::Vector3d& u) {
    xx += u.x() * u.x();
    xy += u.x() * u.y();
    xz += u.x() * u.z();
    yy += u.y() * u.y();
    yz += u.y() * u.z();
    zz += u.z() * u.z();
  }
  Eigen::Matrix3d ToMatrix() const {
    Eigen::Matrix3d S;
    S << xx, xy, xz, xy, yy, yz, xz, yz, zz;
    return S;
  }
};

}  // namespace

bool IsUsableNormal(const Eigen::Vector3d& u) {
  const double n2 = u.squaredNorm();
  return std::isfinite(n2) && n2 > 1e-24;  // NaN or inf in any component fails
}

void RvWorkspace::Load(const ConstraintList& constraints) {
  const size_t n = constraints.size();
  u.resize(n);
  d.resize(n);
  cls.resize(n);
  num_usable = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d& normal = constraints[i].normal_world;
    if (IsUsableNormal(normal)) {
      u[i] = normal.normalized();  // Alg. 1 step 1
      cls[i] = VectorClass::kCoplanar;
      ++num_usable;
    } else {
      u[i].setZero();
      cls[i] = VectorClass::kUnusable;
    }
    d[i] = 0.0;
  }
}

Eigen::Matrix3d NormalScatter(const RvWorkspace& ws, VectorClass which) {
  SymmetricSum S;
  for (int i = 0; i < ws.size(); ++i) {
    if (ws.cls[i] == which) S.Add(ws.u[i]);
  }
  return S.ToMatrix();
}

PlaneFit FitPlane(const Eigen::Matrix3d& S) {
  PlaneFit fit;
  if (!(S.trace() > 0.0) || !S.allFinite()) return fit;  // no direction at all
  // S = A^T A, so its eigenvectors are the right singular vectors of A (Eq. 14)
  // and the smallest eigenvalue's one is the last column of V.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(S);
  fit.eigenvalues = solver.eigenvalues();  // ascending
  Eigen::Vector3d n = solver.eigenvectors().col(0).normalized();
  int largest = 0;
  n.cwiseAbs().maxCoeff(&largest);
  if (n(largest) < 0.0) n = -n;
  fit.n_alpha = n;
  return fit;
}

void ComputeDistances(const Eigen::Vector3d& n_alpha, RvWorkspace* ws) {
  for (int i = 0; i < ws->size(); ++i) {
    ws->d[i] = ws->cls[i] == VectorClass::kUnusable ? 0.0 : CoplanarityDistance(ws->u[i], n_alpha);
  }
}

CriterionResult EvaluateCriterion(const RvOptions& options, const ConstraintList& constraints,
                                  RvWorkspace* ws) {
  RVLIO_CHECK(ws != nullptr);
  CriterionResult result;
  ws->Load(constraints);                                  // Alg. 1 steps 1-2
  result.S = NormalScatter(*ws, VectorClass::kCoplanar);  // all usable vectors
  result.fit = FitPlane(result.S);                        // steps 3-5
  result.num_usable = ws->num_usable;
  const Eigen::Vector3d n = result.fit.n_alpha;
  for (int i = 0; i < ws->size(); ++i) {
    if (ws->cls[i] != VectorClass::kCoplanar) continue;
    const double d = CoplanarityDistance(ws->u[i], n);  // step 6, Eq. (15)
    ws->d[i] = d;
    if (d > options.eps0) {
      ws->cls[i] = VectorClass::kScv;  // step 8
    } else {
      ++result.num_within_eps0;
    }
  }
  if (result.num_usable > 0) {
    result.coplanar_fraction =
        static_cast<double>(result.num_within_eps0) / static_cast<double>(result.num_usable);
  }
  // Proposition 1: "most" vectors lie in alpha.
  result.active = result.num_usable > 0 && result.num_usable >= options.min_constraints &&
                  result.coplanar_fraction >= options.activation_ratio;
  return result;
}

}  // namespace rvlio
