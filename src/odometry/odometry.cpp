#include "rvlio/odometry/odometry.h"

#include "rvlio/odometry/ieskf_odometry.h"

namespace rvlio {

const char* ScanStatusName(ScanStatus s) {
  switch (s) {
    case ScanStatus::kUpdated: return "updated";
    case ScanStatus::kMapInit: return "map_init";
    case ScanStatus::kPredictOnly: return "predict_only";
    case ScanStatus::kDiverged: return "diverged";
  }
  return "unknown";
}

StatusOr<std::unique_ptr<Odometry>> Odometry::Create(const OdometryOptions& options) {
  OdometryOptions checked = options;
  if (Status s = checked.Validate(); !s.ok()) return s;
  if (options.backend == "ieskf") return std::unique_ptr<Odometry>(new IeskfOdometry(options));
  return Status::InvalidInput("backend '" + options.backend +
                              "' is not in this build yet (the smoother lands with issue 6); "
                              "use backend=ieskf");
}

}  // namespace rvlio
