#pragma once
// Sliding-window smoother and batch refinement (docs/design.md "The backends").
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct SmootherOptions {
  int window_size = 10;              // scans in the window
  int association_rounds = 2;        // re-association rounds per new scan
  int max_solver_iterations = 6;     // Ceres iterations per round
  bool solve_unchanged_rounds = false;  // solve a round even when its association changed no scan
  double function_tolerance = 1e-6;     // Ceres: stop when the relative cost change is below this
  double refine_huber_delta = 0.1;   // m, Huber width on the point-to-plane residuals of refine
  int refine_rounds = 4;             // outer rounds of `rvlio refine`
  int refine_chunk_scans = 2000;     // scans per refine chunk (long sequences)
  int refine_solver_iterations = 10; // Ceres iterations per refine round (and chunk)
  int refine_threads = 0;            // threads of `rvlio refine` (association, Ceres); 0: all cores
  int refine_plane_window = 100;     // scans: a plane moves with its source scan within this distance
  double refine_job_overlap_s = 10.0; // s shared by neighbouring chunk jobs (refine --chunk K --of N)
  bool refine_summarize_pairs = true;  // refine: 13-residual summaries of scan pairs (and world planes)
  // Sliding-window backend (backend: smoother).
  std::string linear_solver = "dense_schur";  // Ceres linear solver of the window solve
  std::string map_update = "marginalized";    // when a window scan enters the working map
  double reassociate_min_motion = 0.01;       // m, re-associate a window scan that moved more
  double sliding_window_huber_delta = 0.03;   // m, Huber width on the residuals of the window
  bool estimate_extrinsics = false;           // T_imu_lidar as a window parameter block
  double extrinsic_rot_std = 0.05;            // rad, prior std of the configured extrinsic rotation
  double extrinsic_pos_std = 0.1;             // m, prior std of the configured extrinsic translation

  // The names before the scope was spelled out (read with a warning until
  // the next release): huber_delta was refine's width, online_huber_delta
  // the window's.
  static constexpr DeprecatedName kDeprecatedNames[] = {
      {"huber_delta", "refine_huber_delta"}, {"online_huber_delta", "sliding_window_huber_delta"}};

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
    v.Field("refine_huber_delta", refine_huber_delta, Spec().Unit("m").Positive()
                .Help("Huber width on the point-to-plane residuals of `rvlio refine`"));
    v.Field("refine_rounds", refine_rounds, Spec().Range(1, 50));
    v.Field("refine_chunk_scans", refine_chunk_scans, Spec().Range(10, 1000000));
    v.Field("refine_solver_iterations", refine_solver_iterations, Spec().Range(1, 200));
    v.Field("refine_threads", refine_threads, Spec().Range(0, 256));
    v.Field("refine_plane_window", refine_plane_window, Spec().Range(0, 100000000));
    v.Field("refine_job_overlap_s", refine_job_overlap_s, Spec().Unit("s").Range(0.0, 1e6)
                .Help("seconds of scans shared by neighbouring chunks of `rvlio refine --chunk K "
                      "--of N` (half on each side of a border); `rvlio merge` aligns and blends "
                      "the chunks over them"));
    v.Field("refine_summarize_pairs", refine_summarize_pairs, Spec().Help(
        "`rvlio refine`: a scan's constraints against one source scan (and its world-fixed ones) "
        "as one exact 13-residual summary when they are many (same cost, less memory); false: "
        "one residual per constraint"));
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
