#pragma once
// The control file of `rvlio refine --control FILE` (docs/control.md): CSV
// with a header line; columns by name, in any order:
//   name, x, y, z        required; survey coordinates, m
//   role                 control (default) or check
//   sigma_m              standard deviation per axis, m (default control.sigma_m)
//   t_start, t_end       stop-and-go: the rest period on the mark, seconds of
//                        the recording's clock (both or neither)
//   map_x, map_y, map_z  a wall target: where it appears in the --init run's
//                        map.pcd (all three or none)
// A row with map_* is a target; every other row is a stop-and-go mark. An
// empty cell of an optional column takes its default. Lines that are empty
// or start with '#' are skipped. Unknown columns, a missing required column,
// a bad number, a repeated name: InvalidInput naming the file and line.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"

namespace rvlio {

enum class ControlRole { kControl, kCheck };
const char* ControlRoleName(ControlRole role);  // "control", "check"

struct ControlRow {
  int line = 0;  // 1-based line of the file
  std::string name;
  Eigen::Vector3d p_survey = Eigen::Vector3d::Zero();
  ControlRole role = ControlRole::kControl;
  double sigma_m = 0.0;  // 0: control.sigma_m
  bool has_times = false;
  TimeNs t_start_ns = 0, t_end_ns = 0;
  bool target = false;
  Eigen::Vector3d p_map = Eigen::Vector3d::Zero();  // target: in the --init run's map
};

StatusOr<std::vector<ControlRow>> ReadControlFile(const std::string& path);
// The same from the file's text (`path` names it in errors).
StatusOr<std::vector<ControlRow>> ParseControlFile(const std::string& text,
                                                   const std::string& path);

// One row of control.csv.
struct ControlResidual {
  ControlRow row;
  std::string kind;  // "mark" or "target"
  double sigma_m = 0.0;
  TimeNs t_ns = 0;  // mark: the tie time (middle of the rest period); target: first sighting
  int scans = 0;    // target: the scans that tie it
  bool estimated = false;
  Eigen::Vector3d p_estimated = Eigen::Vector3d::Zero();  // survey frame
  Eigen::Vector3d Residual() const { return p_estimated - row.p_survey; }
};

// The residuals of one role's estimated rows (summary.json "control"), m.
struct ControlRoleSummary {
  int count = 0;  // rows of the role with an estimate
  double rms_m = 0.0;
  Eigen::Vector3d rms_xyz_m = Eigen::Vector3d::Zero();  // per survey axis
  double max_m = 0.0;
  std::string max_name;  // the row of the largest residual (the later of equals)
};
ControlRoleSummary SummarizeControlRole(const std::vector<ControlResidual>& rows, ControlRole role);

// control.csv's text of the rows (name, role, kind, x, y, z, x_est, y_est,
// z_est, dx, dy, dz, d3d, sigma_m, t_s, scans; coordinates with 4 decimals;
// the estimate's cells empty when there is none) and back (InvalidInput
// naming the file and line).
std::string ControlCsvText(const std::vector<ControlResidual>& rows);
StatusOr<std::vector<ControlResidual>> ParseControlCsv(const std::string& text,
                                                       const std::string& path);

}  // namespace rvlio
