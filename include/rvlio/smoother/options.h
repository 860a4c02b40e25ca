#pragma once
// Sliding-window smoother and batch refinement (DESIGN.md section 5).
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct SmootherOptions {
  int window_size = 10;              // scans in the window
  int association_rounds = 2;        // re-association rounds per new scan
  int max_solver_iterations = 6;     // Ceres iterations per round
  double huber_delta = 0.1;          // m, robust kernel on point-to-plane residuals
  int refine_rounds = 4;             // outer rounds of `rvlio refine`
  int refine_chunk_scans = 2000;     // scans per refine chunk (long sequences)
  int refine_solver_iterations = 10; // Ceres iterations per refine round (and chunk)
  int refine_threads = 0;            // threads of `rvlio refine` (association, Ceres); 0: all cores

  template <class V>
  void Visit(V& v) {
    v.Field("window_size", window_size, Spec().Range(2, 200));
    v.Field("association_rounds", association_rounds, Spec().Range(1, 20));
    v.Field("max_solver_iterations", max_solver_iterations, Spec().Range(1, 200));
    v.Field("huber_delta", huber_delta, Spec().Unit("m").Positive());
    v.Field("refine_rounds", refine_rounds, Spec().Range(1, 50));
    v.Field("refine_chunk_scans", refine_chunk_scans, Spec().Range(10, 1000000));
    v.Field("refine_solver_iterations", refine_solver_iterations, Spec().Range(1, 200));
    v.Field("refine_threads", refine_threads, Spec().Range(0, 256));
  }
  Status Validate() { return ValidateFields(*this, "smoother"); }
};

}  // namespace rvlio
