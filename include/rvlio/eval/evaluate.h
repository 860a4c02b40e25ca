#pragma once
// The whole evaluation of `rvlio eval`: associate, align, APE, RPE, end-point
// and along-axis error (docs/design.md "Evaluation").
#include <cstddef>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/eval/align.h"
#include "rvlio/eval/metrics.h"
#include "rvlio/eval/options.h"
#include "rvlio/eval/stats.h"
#include "rvlio/eval/time_matching.h"

namespace rvlio {

struct EvalResult {
  size_t matched = 0;
  Association association;  // the matched poses: indices into ref and est, in order
  AlignMode align = AlignMode::kSe3;  // the alignment used (origin after a fallback)
  Similarity3 T_ref_est;
  Similarity3 T_ref_est_poses;  // PoseAlignment of the matched poses (for maps)
  ErrorStats ape_m;        // APE translation
  ErrorStats ape_rot_deg;  // APE rotation angle
  RpeResult rpe;           // on the aligned estimate (Sim3 scale applies)
  double end_point_error_m = 0.0;
  AlongAxisError along_axis;
  std::vector<std::string> warnings;
};

// Errors (bad input): invalid options, empty or unordered trajectories, no
// matching stamps, an RPE delta that leaves no pair.
StatusOr<EvalResult> Evaluate(const Trajectory& ref, const Trajectory& est, EvalOptions options);

}  // namespace rvlio
