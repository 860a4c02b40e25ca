#pragma once
// The options of batch refinement (`rvlio refine`, config section `refine`;
// docs/refine.md). Until the next release the keys are also read under their
// former names in the smoother's section (smoother.refine_rounds, ...), with
// a warning: Configuration::kMovedKeys (config/configuration.h).
#include "rvlio/common/options.h"

namespace rvlio {

struct RefineOptions {
  double huber_delta = 0.1;    // m, Huber width on the point-to-plane residuals
  int rounds = 4;              // outer rounds
  int chunk_scans = 2000;      // scans per chunk of the solve (long sequences)
  int solver_iterations = 10;  // Ceres iterations per round (and chunk)
  int threads = 0;             // association and Ceres threads; 0: all cores
  int plane_window = 100;      // scans: a plane moves with its source scan within this distance
  double job_overlap_s = 10.0;  // s shared by neighbouring chunk jobs (refine --chunk K --of N)
  bool summarize_pairs = true;  // 13-residual summaries of scan pairs (and world planes)

  template <class V>
  void Visit(V& v) {
    v.Field("huber_delta", huber_delta, Spec().Unit("m").Positive()
                .Help("Huber width on the point-to-plane residuals of `rvlio refine`"));
    v.Field("rounds", rounds, Spec().Range(1, 50).Help("outer rounds of `rvlio refine`"));
    v.Field("chunk_scans", chunk_scans, Spec().Range(10, 1000000)
                .Help("scans per chunk of refine's solve (long sequences)"));
    v.Field("solver_iterations", solver_iterations, Spec().Range(1, 200)
                .Help("Ceres iterations per refine round (and chunk)"));
    v.Field("threads", threads, Spec().Range(0, 256)
                .Help("threads of `rvlio refine` (association, Ceres); 0: all cores"));
    v.Field("plane_window", plane_window, Spec().Range(0, 100000000)
                .Help("a plane fitted mostly to scan j's points moves with scan j for the scans "
                      "within this many scans of j (0: world-fixed planes only)"));
    v.Field("job_overlap_s", job_overlap_s, Spec().Unit("s").Range(0.0, 1e6)
                .Help("seconds of scans shared by neighbouring chunks of `rvlio refine --chunk K "
                      "--of N` (half on each side of a border); `rvlio merge` aligns and blends "
                      "the chunks over them"));
    v.Field("summarize_pairs", summarize_pairs, Spec().Help(
        "`rvlio refine`: a scan's constraints against one source scan (and its world-fixed ones) "
        "as one exact 13-residual summary when they are many (same cost, less memory); false: "
        "one residual per constraint"));
  }
  Status Validate() { return ValidateFields(*this, "refine"); }
};

}  // namespace rvlio
