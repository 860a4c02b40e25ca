#include "rvlio/eval/evaluate.h"

#include "rvlio/eval/time_matching.h"

namespace rvlio {

// Recipe: Associate -> Align -> APE -> RPE -> end point -> along axis.
StatusOr<EvalResult> Evaluate(const Trajectory& ref, const Trajectory& est, EvalOptions options) {
  if (Status s = options.Validate(); !s.ok()) return s;
  StatusOr<AlignMode> mode = ParseAlignMode(options.align);
  if (!mode.ok()) return mode.status();
  StatusOr<Association> association = Associate(ref, est, options.max_dt);
  if (!association.ok()) return association.status();
  Trajectory ref_m, est_m;
  ApplyAssociation(*association, ref, est, &ref_m, &est_m);

  AlignOptions align_options;
  align_options.min_lateral_ratio = options.min_lateral_ratio;
  align_options.min_poses = static_cast<size_t>(options.min_align_poses);
  AlignmentResult alignment = Align(ref_m, est_m, *mode, align_options);
  const Trajectory est_aligned = alignment.T_ref_est.Apply(est_m);

  RpeOptions rpe_options;
  rpe_options.delta = options.rpe_delta;
  rpe_options.unit = options.rpe_unit == "meters" ? RpeUnit::kMeters : RpeUnit::kFrames;
  StatusOr<RpeResult> rpe = ComputeRpe(ref_m, est_aligned, rpe_options);
  if (!rpe.ok()) return rpe.status();

  EvalResult r;
  r.matched = association->size();
  r.align = alignment.used;
  r.T_ref_est = alignment.T_ref_est;
  r.T_ref_est_poses = PoseAlignment(ref_m, est_m);
  r.warnings = std::move(alignment.warnings);
  r.ape_m = ComputeStats(ApeTranslationErrors(ref_m, est_aligned));
  r.ape_rot_deg = ComputeStats(ApeRotationErrorsDeg(ref_m, est_aligned));
  r.rpe = *rpe;
  r.end_point_error_m = EndPointError(ref_m, est_aligned);
  r.along_axis = ComputeAlongAxisError(ref_m, est_aligned);
  r.association = std::move(*association);
  return r;
}

}  // namespace rvlio
