#pragma once
// The options of the online odometry (rvlio::Odometry): one section per
// module. The whole configuration that `--config` files and `--set
// key=value` fill adds the sections the other layers read
// (config/configuration.h).
#include <string>
#include <utility>

#include "rvlio/common/options.h"
#include "rvlio/constraints/options.h"
#include "rvlio/degeneracy/options.h"
#include "rvlio/ieskf/options.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/lidar/options.h"
#include "rvlio/map/options.h"
#include "rvlio/odometry/divergence_options.h"
#include "rvlio/odometry/localization_options.h"
#include "rvlio/rv/options.h"
#include "rvlio/window/options.h"

namespace rvlio {

// The estimator of a run; written ieskf | smoother in the configuration.
enum class Backend { kIeskf, kSmoother };

template <>
struct EnumNames<Backend> {
  static constexpr std::pair<Backend, const char*> kNames[] = {{Backend::kIeskf, "ieskf"},
                                                               {Backend::kSmoother, "smoother"}};
};

struct OdometryOptions {
  Backend backend = Backend::kIeskf;
  LidarOptions lidar;
  ImuOptions imu;
  ExtrinsicsSection extrinsics;
  MapOptions map;
  ConstraintOptions constraints;
  RvOptions rv;
  DegeneracyOptions degeneracy;
  IeskfOptions ieskf;
  SmootherOptions smoother;
  DivergenceOptions divergence;
  LocalizationOptions localization;  // used only with a reference map (`run --map`)

  template <class V>
  void Visit(V& v) {
    v.Field("backend", backend, Spec().Choices(EnumChoices<Backend>()).Help("estimator"));
    v.Section("lidar", lidar);
    v.Section("imu", imu);
    v.Section("extrinsics", extrinsics);
    v.Section("map", map);
    v.Section("constraints", constraints);
    v.Section("rv", rv);
    v.Section("degeneracy", degeneracy);
    v.Section("ieskf", ieskf);
    v.Section("smoother", smoother);
    v.Section("divergence", divergence);
    v.Section("localization", localization);
  }

  // Ranges and choices of every key, then the cross-field rules of each module.
  Status Validate() {
    Status s = ValidateFields(*this);
    if (!s.ok()) return s;
    for (Status m : {lidar.Validate(), imu.Validate(), extrinsics.Validate(), map.Validate(),
                     constraints.Validate(), rv.Validate(), degeneracy.Validate(), ieskf.Validate(), smoother.Validate(),
                     divergence.Validate(), localization.Validate()})
      if (!m.ok()) return m;
    if (backend == Backend::kSmoother && lidar.estimate_time_offset && smoother.estimate_extrinsics)
      return Status::InvalidInput(
          "lidar.estimate_time_offset and smoother.estimate_extrinsics: the smoother estimates "
          "one of them at a time (the IESKF both)");
    return Status::Ok();
  }
};

}  // namespace rvlio
