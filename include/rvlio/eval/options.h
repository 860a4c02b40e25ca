#pragma once
// Options of the trajectory evaluation (docs/design.md "Evaluation"; definitions of
// evo, see evo_reference/README.md).
#include <cmath>
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct EvalOptions {
  std::string align = "se3";        // se3 | sim3 | origin | none
  double max_dt = 0.01;             // s, largest |t_ref - t_est| of an associated pair
  double rpe_delta = 1.0;           // frames (integer) or metres of travelled path
  std::string rpe_unit = "frames";  // frames | meters
  // Umeyama needs a reference that is not a straight line: when the second
  // principal standard deviation of the reference positions is below this
  // fraction of the first, alignment falls back to "origin" with a warning.
  double min_lateral_ratio = 1e-3;
  int min_align_poses = 3;  // fewer matched poses: fall back to "origin"

  template <class V>
  void Visit(V& v) {
    v.Field("align", align,
            Spec().Choices({"se3", "sim3", "origin", "none"}).Help("alignment of the estimate"));
    v.Field("max_dt", max_dt, Spec().Unit("s").Min(0.0).Help("association tolerance"));
    v.Field("rpe_delta", rpe_delta, Spec().Positive().Help("RPE step, in rpe_unit"));
    v.Field("rpe_unit", rpe_unit, Spec().Choices({"frames", "meters"}).Help("unit of rpe_delta"));
    v.Field("min_lateral_ratio", min_lateral_ratio,
            Spec().Range(0.0, 1.0).Help("collinearity threshold of the Umeyama fallback"));
    v.Field("min_align_poses", min_align_poses,
            Spec().Min(1).Help("fewest matched poses for Umeyama"));
  }

  // Field ranges, then: a frame delta must be a whole number.
  Status Validate() {
    Status s = ValidateFields(*this, "eval");
    if (!s.ok()) return s;
    if (rpe_unit == "frames" && std::floor(rpe_delta) != rpe_delta)
      return Status::InvalidInput("eval.rpe_delta = " + std::to_string(rpe_delta) +
                                  " must be a whole number of frames");
    return Status::Ok();
  }
};

}  // namespace rvlio
