#pragma once
// The degeneracy stage: which treatment of weak (degenerate) directions the
// estimator applies, and each method's parameters (docs/degeneracy.md).
#include <string>
#include <utility>

#include "rvlio/common/options.h"
#include "rvlio/rv/options.h"

namespace rvlio {

enum class DegeneracyMethod { kRv, kRemap, kLocalizability, kRegularized, kNone };

template <>
struct EnumNames<DegeneracyMethod> {
  static constexpr std::pair<DegeneracyMethod, const char*> kNames[] = {
      {DegeneracyMethod::kRv, "rv"},
      {DegeneracyMethod::kRemap, "remap"},
      {DegeneracyMethod::kLocalizability, "localizability"},
      {DegeneracyMethod::kRegularized, "regularized"},
      {DegeneracyMethod::kNone, "none"}};
};

// How remap acts in the sliding-window smoother (docs/degeneracy.md
// "Backends"): the scan's plane factor loses its say along the degenerate
// directions and the window's IMU chain places the pose there (project), or
// a stiff prior holds the pose at its IMU prediction there, as localizability
// does (hold).
enum class RemapWindowForm { kProject, kHold };

template <>
struct EnumNames<RemapWindowForm> {
  static constexpr std::pair<RemapWindowForm, const char*> kNames[] = {
      {RemapWindowForm::kProject, "project"}, {RemapWindowForm::kHold, "hold"}};
};

// Every threshold is on the information with sigma = 1 (sum of w_i h_i^T h_i
// over the scan's point-to-plane rows: the estimator's H^T R^-1 H times
// lidar_noise^2), so it does not move with constraints.lidar_noise.
struct DegeneracyOptions {
  DegeneracyMethod method = DegeneracyMethod::kRv;
  // Solution remapping (Zhang, Kaess, Singh 2016): an eigenvalue of the 6x6
  // pose information below this marks a degenerate direction. The paper
  // leaves the value to experiment; 100 is the threshold of its authors'
  // released LOAM mapping stage (also sigma-free, unit-weighted rows).
  double remap_min_eigenvalue = 100.0;
  // X-ICP localizability (Tuna et al. 2023): contributions |h_i . v_k| below
  // the filter threshold are dropped; a direction whose sum of kept
  // contributions is below the localizability threshold is held fixed.
  double localizability_min_contribution = 0.3;
  double localizability_translation_min = 200.0;
  double localizability_rotation_min = 200.0;
  // DCReg-style regularization: a Schur-complement block (rotation or
  // translation) eigenvalue below lambda_max / max_condition is weak; the
  // damping raises it to lambda_max / max_condition along its eigenvector.
  double regularized_max_condition = 10.0;
  // The smoother and refine (no explicit increment): remap and
  // localizability hold the scan's pose at its anchor (the IMU prediction in
  // the smoother, the --init pose in refine) along the held directions by a
  // prior of this information (sigma = 1, like the thresholds): the pose's
  // standard deviation along a held direction is constraints.lidar_noise /
  // sqrt(hold_information), 1/1000 of the noise with the default. Stiff
  // against a scan's own information (sums of 1e3-1e5), not so stiff that
  // the solver's normal equations lose precision.
  double hold_information = 1e6;
  // remap in the smoother: project (default; the paper's "the degenerate
  // directions come from the prior", the prior being the rest of the window)
  // or hold (a prior at the IMU prediction, localizability's form).
  RemapWindowForm remap_window_form = RemapWindowForm::kProject;
  // remap in refine: hold (default; a prior at the --init pose, which is
  // Zhang et al.'s remap of an iterative solve started there) or project
  // (the scan's pair factors have no say along the weak directions in either
  // pose, and the IMU chain places the poses; docs/degeneracy.md "Backends").
  RemapWindowForm remap_refine_form = RemapWindowForm::kHold;

  template <class V>
  void Visit(V& v) {
    v.Field("method", method, Spec().Choices(EnumChoices<DegeneracyMethod>())
                                  .Help("rv | remap | localizability | regularized | none"));
    v.Field("remap_min_eigenvalue", remap_min_eigenvalue, Spec().Positive()
        .Help("remap: pose-information eigenvalue (sigma = 1) below which a direction is degenerate"));
    v.Field("localizability_min_contribution", localizability_min_contribution, Spec().Range(0.0, 1.0)
        .Help("localizability: contributions |h.v| below this are filtered out"));
    v.Field("localizability_translation_min", localizability_translation_min, Spec().Positive()
        .Help("localizability: translation direction held when its filtered sum is below this"));
    v.Field("localizability_rotation_min", localizability_rotation_min, Spec().Positive()
        .Help("localizability: rotation direction held when its filtered sum is below this"));
    v.Field("regularized_max_condition", regularized_max_condition, Spec().Range(1.0, 1e12)
        .Help("regularized: Schur-block eigenvalues below lambda_max / this are damped up to it"));
    v.Field("hold_information", hold_information, Spec().Range(1.0, 1e12)
        .Help("smoother/refine, remap and localizability: information (sigma = 1) of the prior holding a weak direction"));
    v.Field("remap_window_form", remap_window_form, Spec().Choices(EnumChoices<RemapWindowForm>())
        .Help("smoother, remap: project (the scan's factor has no say along the degenerate directions) | hold (a prior at the IMU prediction)"));
    v.Field("remap_refine_form", remap_refine_form, Spec().Choices(EnumChoices<RemapWindowForm>())
        .Help("refine, remap: hold (a prior at the --init pose) | project (the scan's factors have no say along the degenerate directions, in its pose and in the poses of the scans whose planes it uses)"));
  }
  Status Validate() { return ValidateFields(*this, "degeneracy"); }
};

// The RV switches a run uses: RV runs only when it is the selected method
// (method none, like every other method, leaves the constraint list as
// associated).
inline RvOptions EffectiveRvOptions(RvOptions rv, const DegeneracyOptions& degeneracy) {
  rv.enabled = rv.enabled && degeneracy.method == DegeneracyMethod::kRv;
  return rv;
}

}  // namespace rvlio
