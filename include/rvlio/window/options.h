#pragma once
// The sliding-window smoother (docs/design.md "The backends"); refine's keys: refine/options.h.
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct SmootherOptions {
  int window_size = 10;              // scans in the window
  int association_rounds = 2;        // re-association rounds per new scan
  int max_solver_iterations = 6;     // Ceres iterations per round
  bool solve_unchanged_rounds = false;  // solve a round even when its association changed no scan
  double function_tolerance = 1e-6;     // Ceres: stop when the relative cost change is below this
  std::string linear_solver = "dense_schur";  // Ceres linear solver of the window solve
  std::string map_update = "marginalized";    // when a window scan enters the working map
  double reassociate_min_motion = 0.01;       // m, re-associate a window scan that moved more
  double sliding_window_huber_delta = 0.03;   // m, Huber width on the residuals of the window
  bool estimate_extrinsics = false;           // T_imu_lidar as a window parameter block
  double extrinsic_rot_std = 0.05;            // rad, prior std of the configured extrinsic rotation
  double extrinsic_pos_std = 0.1;             // m, prior std of the configured extrinsic translation

  // The name before the scope was spelled out (read with a warning until the
  // next release). Refine's former keys here (refine_rounds, huber_delta, ...)
  // moved to the section `refine` (Configuration::kMovedKeys).
  static constexpr DeprecatedName kDeprecatedNames[] = {
      {"online_huber_delta", "sliding_window_huber_delta"}};

  template <class V>
  void Visit(V& v) {
    v.Field("window_size", window_size, Spec().Range(2, 200));
    v.Field("association_rounds", association_rounds, Spec().Range(1, 20));
    v.Field("max_solver_iterations", max_solver_iterations, Spec().Range(1, 200));
    v.Field("function_tolerance", function_tolerance, Spec().Range(1e-12, 1e-1).Help(
        "Ceres function tolerance of the sliding-window solve: a solve stops when an iteration "
        "changes the cost by less than this fraction"));
    v.Field("solve_unchanged_rounds", solve_unchanged_rounds, Spec().Help(
        "solve an association round after the first even when it re-associated no scan (the "
        "same problem again: more Ceres iterations, no new constraints); false ends Optimize there"));
    v.Field("linear_solver", linear_solver,
            Spec().Choices({"dense_schur", "dense_normal_cholesky", "sparse_normal_cholesky", "dense_qr"})
                .Help("Ceres linear solver of the sliding-window solve"));
    v.Field("map_update", map_update, Spec().Choices({"marginalized", "newest"})
                .Help("a scan enters the working map when marginalized (final estimate) or right after its first solve"));
    v.Field("reassociate_min_motion", reassociate_min_motion, Spec().Unit("m").Range(0.0, 10.0)
                .Help("re-associate a window scan when it moved more than this (translation + 10 m x rotation in rad)"));
    v.Field("sliding_window_huber_delta", sliding_window_huber_delta, Spec().Unit("m").Positive()
                .Help("Huber width on the point-to-plane residuals of the sliding window (backend: smoother)"));
    v.Field("estimate_extrinsics", estimate_extrinsics, Spec().Help(
        "estimate T_imu_lidar in the sliding window (backend: smoother); an axis the motion does "
        "not excite stays at the configured value (summary.json: extrinsic)"));
    v.Field("extrinsic_rot_std", extrinsic_rot_std, Spec().Unit("rad").Positive()
        .Help("prior std of the configured extrinsic rotation (estimate_extrinsics)"));
    v.Field("extrinsic_pos_std", extrinsic_pos_std, Spec().Unit("m").Positive()
        .Help("prior std of the configured extrinsic translation (estimate_extrinsics)"));
  }
  Status Validate() { return ValidateFields(*this, "smoother"); }
};

}  // namespace rvlio
