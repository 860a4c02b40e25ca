#include "rvlio/rv/reinforce.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio {

namespace {

// Marks coplanar vectors with d_i > eps0 as SCVs and removes their rows from
// the scatter S (Alg. 2 step 5: "delete rows in A"). Returns how many.
int DropNewScvs(double eps0, bool only_marked, RvWorkspace* ws, Eigen::Matrix3d* S,
                int* num_coplanar) {
  int dropped = 0;
  for (int i = 0; i < ws->size(); ++i) {
    const bool is_new = only_marked ? ws->cls[i] == VectorClass::kScv
                                    : ws->cls[i] == VectorClass::kCoplanar && ws->d[i] > eps0;
    if (!is_new) continue;
    ws->cls[i] = VectorClass::kScv;
    S->noalias() -= ws->u[i] * ws->u[i].transpose();
    ++dropped;
  }
  *num_coplanar -= dropped;
  return dropped;
}

}  // namespace

RefitResult RefitPlane(const RvOptions& options, const Eigen::Matrix3d& S_all,
                       const PlaneFit& initial, RvWorkspace* ws) {
  RVLIO_CHECK(ws != nullptr);
  RefitResult result;
  result.fit = initial;
  Eigen::Matrix3d S = S_all;
  int num_coplanar = ws->num_usable;
  // The SCVs of Alg. 1 are already marked: remove their rows first.
  int num_new = DropNewScvs(options.eps0, /*only_marked=*/true, ws, &S, &num_coplanar);
  while (num_new > 0 && num_coplanar > 0) {
    if (result.iterations >= options.max_iterations) {
      result.converged = false;
      break;
    }
    result.fit = FitPlane(S);  // Alg. 2 step 6 (Alg. 1 steps 3-5)
    ++result.iterations;
    ComputeDistances(result.fit.n_alpha, ws);  // step 4, Eq. (15) for all vectors
    num_new = DropNewScvs(options.eps0, /*only_marked=*/false, ws, &S, &num_coplanar);
  }
  result.num_coplanar = num_coplanar;
  result.num_scv = ws->num_usable - num_coplanar;
  return result;
}

double ReinforcementCoefficient(const RvOptions& options, int num_scv, int num_coplanar) {
  RVLIO_CHECK(options.k0 > 0.0 && std::isfinite(options.k0));
  RVLIO_CHECK(num_scv >= 0 && num_coplanar >= 0);
  // Eq. (19): K = k0 * size(u_s) / size(u_c); undefined without coplanar vectors.
  double K = num_coplanar > 0
                 ? options.k0 * static_cast<double>(num_scv) / static_cast<double>(num_coplanar)
                 : 1.0;
  if (options.clamp) K = std::min(K, 1.0);
  // Our addition (not in the paper): a floor on K caps the information gain of
  // one SCV at 1 / min_K. Without it a handful of SCVs among a thousand wall
  // vectors get K ~ 0.01, i.e. 100x weight, and one mis-associated feature
  // normal can then drag the estimate along the unobservable axis (measured on
  // the corridor and loopback presets, docs/rv_modules.md "How the defaults
  // were chosen").
  return num_scv > 0 ? std::max(K, options.min_K) : K;
}

int ReinforceScv(double K, const RvWorkspace& ws, ConstraintList* constraints,
                 double max_abs_residual_m) {
  RVLIO_CHECK(constraints != nullptr && ws.size() == static_cast<int>(constraints->size()));
  RVLIO_CHECK(K > 0.0 && std::isfinite(K));
  // R_i = sigma^2 / weight  ->  K R_i  <=>  weight / K.
  const double scale = 1.0 / K;
  int edited = 0;
  for (int i = 0; i < ws.size(); ++i) {
    if (ws.cls[i] != VectorClass::kScv) continue;
    Constraint& c = (*constraints)[i];
    c.role = RvRole::kScv;
    if (max_abs_residual_m > 0.0 && std::abs(c.residual) > max_abs_residual_m) continue;
    c.weight *= scale;
    ++edited;
  }
  return edited;
}

}  // namespace rvlio
