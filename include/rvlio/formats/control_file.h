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

}  // namespace rvlio
