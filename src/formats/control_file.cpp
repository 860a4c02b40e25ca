#include "rvlio/formats/control_file.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "rvlio/common/text.h"
#include "rvlio/common/check.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

const char* const kColumns[] = {"name",    "x",     "y",     "z",     "role", "sigma_m",
                                "t_start", "t_end", "map_x", "map_y", "map_z"};

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

// A cell as an error message shows it: printable ASCII (others '?'), at most
// 40 characters (a binary file's "header" stays one short line).
std::string Shown(const std::string& cell) {
  std::string out;
  for (char c : cell.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
  return cell.size() > 40 ? out + "..." : out;
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

// Parses one row; the columns are known to exist where required.
class RowParser {
 public:
  RowParser(const std::string& path, int line, const std::map<std::string, size_t>& columns,
            const std::vector<std::string>& cells)
      : where_(path + " line " + std::to_string(line)), columns_(columns), cells_(cells) {}

  std::string Cell(const char* column) const {
    const auto it = columns_.find(column);
    return it == columns_.end() ? std::string() : cells_[it->second];
  }
  Status Error(const std::string& what) const { return Status::InvalidInput(where_ + ": " + what); }

  // A finite number; *present false (and Ok) for an empty optional cell.
  Status Number(const char* column, double* v, bool* present = nullptr) const {
    const std::string text = Cell(column);
    if (present != nullptr) *present = !text.empty();
    if (text.empty() && present != nullptr) return Status::Ok();
    char* end = nullptr;
    *v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(*v))
      return Error(std::string(column) + " '" + Shown(text) + "' is not a number");
    return Status::Ok();
  }

  Status Parse(ControlRow* row) const {
    row->name = Cell("name");
    if (row->name.empty()) return Error("the name is empty");
    for (int a = 0; a < 3; ++a)
      if (Status s = Number(kColumns[1 + a], &row->p_survey[a]); !s.ok()) return s;
    const std::string role = Cell("role");
    if (role == "check") row->role = ControlRole::kCheck;
    else if (role.empty() || role == "control") row->role = ControlRole::kControl;
    else return Error("role '" + Shown(role) + "' is neither control nor check");
    bool has = false;
    if (Status s = Number("sigma_m", &row->sigma_m, &has); !s.ok()) return s;
    if (has && row->sigma_m <= 0.0) return Error("sigma_m must be positive");
    if (Status s = Times(row); !s.ok()) return s;
    return Target(row);
  }

 private:
  // Seconds to the nanosecond as written (ParseSecondsToNs: no double in
  // between, which keeps only ~0.2 us at 1.7e9 s).
  Status Time(const char* column, TimeNs* t_ns, bool* present) const {
    const std::string text = Cell(column);
    *present = !text.empty();
    if (*present && !ParseSecondsToNs(text, t_ns))
      return Error(std::string(column) + " '" + Shown(text) + "' is not a time in seconds");
    return Status::Ok();
  }

  Status Times(ControlRow* row) const {
    bool has0 = false, has1 = false;
    if (Status s = Time("t_start", &row->t_start_ns, &has0); !s.ok()) return s;
    if (Status s = Time("t_end", &row->t_end_ns, &has1); !s.ok()) return s;
    if (has0 != has1) return Error("t_start and t_end go together (both or neither)");
    if (!has0) return Status::Ok();
    if (row->t_end_ns <= row->t_start_ns) return Error("t_end must be after t_start");
    row->has_times = true;
    return Status::Ok();
  }

  Status Target(ControlRow* row) const {
    int present = 0;
    for (int a = 0; a < 3; ++a) {
      bool has = false;
      if (Status s = Number(kColumns[8 + a], &row->p_map[a], &has); !s.ok()) return s;
      present += has ? 1 : 0;
    }
    if (present != 0 && present != 3) return Error("map_x, map_y and map_z go together");
    row->target = present == 3;
    if (row->target && row->has_times)
      return Error("a row is a stop-and-go mark (t_start, t_end) or a target (map_x, map_y, "
                   "map_z), not both");
    return Status::Ok();
  }

  std::string where_;
  const std::map<std::string, size_t>& columns_;
  const std::vector<std::string>& cells_;
};

StatusOr<std::map<std::string, size_t>> HeaderColumns(const std::string& line,
                                                     const std::string& path, int number) {
  const std::string where = path + " line " + std::to_string(number);
  std::map<std::string, size_t> columns;
  const std::vector<std::string> cells = SplitCells(line);
  const std::set<std::string> known(std::begin(kColumns), std::end(kColumns));
  for (size_t i = 0; i < cells.size(); ++i) {
    if (known.count(cells[i]) == 0)
      return Status::InvalidInput(where + ": unknown column '" + Shown(cells[i]) +
                                  "' (columns: name, x, y, z, role, sigma_m, t_start, t_end, "
                                  "map_x, map_y, map_z)");
    if (!columns.emplace(cells[i], i).second)
      return Status::InvalidInput(where + ": column '" + cells[i] + "' appears twice");
  }
  for (const char* required : {"name", "x", "y", "z"})
    if (columns.count(required) == 0)
      return Status::InvalidInput(where + ": the header lacks the column '" +
                                  std::string(required) + "' (required: name, x, y, z)");
  return columns;
}

}  // namespace

const char* ControlRoleName(ControlRole role) {
  return role == ControlRole::kCheck ? "check" : "control";
}

StatusOr<std::vector<ControlRow>> ParseControlFile(const std::string& text,
                                                   const std::string& path) {
  // A spreadsheet's UTF-8 byte-order mark before the header is not a column.
  const bool bom = text.rfind("\xEF\xBB\xBF", 0) == 0;
  std::stringstream in(bom ? text.substr(3) : text);
  std::string line;
  int number = 0;
  std::map<std::string, size_t> columns;
  std::vector<ControlRow> rows;
  std::set<std::string> names;
  while (std::getline(in, line)) {
    ++number;
    const std::string trimmed = Trim(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    if (columns.empty()) {
      StatusOr<std::map<std::string, size_t>> header = HeaderColumns(trimmed, path, number);
      if (!header.ok()) return header.status();
      columns = std::move(*header);
      continue;
    }
    const std::vector<std::string> cells = SplitCells(trimmed);
    if (cells.size() != columns.size())
      return Status::InvalidInput(path + " line " + std::to_string(number) + ": " +
                                  std::to_string(cells.size()) + " cells, the header has " +
                                  std::to_string(columns.size()));
    ControlRow row;
    row.line = number;
    const RowParser parser(path, number, columns, cells);
    if (Status s = parser.Parse(&row); !s.ok()) return s;
    if (!names.insert(row.name).second)
      return parser.Error("the name '" + row.name + "' appears twice");
    rows.push_back(std::move(row));
  }
  if (columns.empty())
    return Status::InvalidInput(path + ": no header line (name,x,y,z[,role,sigma_m,...])");
  if (rows.empty()) return Status::InvalidInput(path + ": no control point");
  return rows;
}

StatusOr<std::vector<ControlRow>> ReadControlFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Status::InvalidInput("the control file '" + path + "' is a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::InvalidInput("cannot read the control file '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) return Status::InvalidInput("cannot read the control file '" + path + "'");
  return ParseControlFile(text.str(), path);
}

constexpr const char* kControlCsvHeader =
    "name,role,kind,x,y,z,x_est,y_est,z_est,dx,dy,dz,d3d,sigma_m,t_s,scans";

ControlRoleSummary SummarizeControlRole(const std::vector<ControlResidual>& rows,
                                        ControlRole role) {
  ControlRoleSummary out;
  double sum2 = 0.0;
  Eigen::Vector3d sum2_axes = Eigen::Vector3d::Zero();
  for (const ControlResidual& r : rows) {
    if (r.row.role != role || !r.estimated) continue;
    const Eigen::Vector3d d = r.Residual();
    ++out.count;
    sum2 += d.squaredNorm();
    sum2_axes += d.cwiseAbs2();
    if (d.norm() >= out.max_m) out.max_m = d.norm(), out.max_name = r.row.name;
  }
  if (out.count == 0) return out;
  out.rms_m = std::sqrt(sum2 / out.count);
  out.rms_xyz_m = (sum2_axes / out.count).cwiseSqrt();
  return out;
}

std::string ControlCsvText(const std::vector<ControlResidual>& rows) {
  std::string text = std::string(kControlCsvHeader) + "\n";
  for (const ControlResidual& r : rows) {
    const Eigen::Vector3d d = r.Residual();
    std::vector<std::string> cells = {r.row.name, ControlRoleName(r.row.role), r.kind};
    for (int a = 0; a < 3; ++a) cells.push_back(FormatFixed(r.row.p_survey[a], 4));
    for (int a = 0; a < 3; ++a) cells.push_back(r.estimated ? FormatFixed(r.p_estimated[a], 4) : "");
    for (int a = 0; a < 3; ++a) cells.push_back(r.estimated ? FormatFixed(d[a], 4) : "");
    cells.push_back(r.estimated ? FormatFixed(d.norm(), 4) : "");
    cells.push_back(FormatG(r.sigma_m));
    cells.push_back(FormatFixed(NsToSeconds(r.t_ns), 3));
    cells.push_back(std::to_string(r.scans));
    text += Join(cells, ",") + "\n";
  }
  return text;
}

namespace {

bool ParseDouble(const std::string& text, double* v) {
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && std::isfinite(*v);
}

// One row of control.csv as ControlResidualText writes it.
bool ParseControlCsvRow(const std::string& line, ControlResidual* r) {
  std::vector<std::string> c;
  std::stringstream cells(line);
  for (std::string cell; std::getline(cells, cell, ',');) c.push_back(cell);
  if (!line.empty() && line.back() == ',') c.push_back("");
  if (c.size() != 16 || (c[1] != "control" && c[1] != "check")) return false;
  r->row.name = c[0];
  r->row.role = c[1] == "check" ? ControlRole::kCheck : ControlRole::kControl;
  r->kind = c[2];
  for (int a = 0; a < 3; ++a)
    if (!ParseDouble(c[3 + a], &r->row.p_survey[a])) return false;
  r->estimated = !c[6].empty();
  for (int a = 0; a < 3 && r->estimated; ++a)
    if (!ParseDouble(c[6 + a], &r->p_estimated[a])) return false;
  if (!ParseDouble(c[13], &r->sigma_m) || !ParseSecondsToNs(c[14], &r->t_ns)) return false;
  r->scans = std::atoi(c[15].c_str());
  return true;
}

}  // namespace

StatusOr<std::vector<ControlResidual>> ParseControlCsv(const std::string& text,
                                                       const std::string& path) {
  std::stringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != kControlCsvHeader)
    return Status::InvalidInput(path + ": not a control.csv of rvlio refine (header)");
  std::vector<ControlResidual> rows;
  for (int number = 2; std::getline(in, line); ++number) {
    ControlResidual r;
    if (!ParseControlCsvRow(line, &r))
      return Status::InvalidInput(path + " line " + std::to_string(number) + ": not a row of " +
                                  kControlCsvHeader);
    rows.push_back(r);
  }
  return rows;
}

}  // namespace rvlio
