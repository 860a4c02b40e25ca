#pragma once
// cell.json as JSON, for the summary (ablate_summary.cpp) and the cell
// records themselves (ablate_cells.cpp); private to the library.
#include <nlohmann/json.hpp>

#include "rvlio/experiments/ablate_cells.h"

namespace rvlio::experiments::ablate {

// cell.json of a finished cell with the plan's hash, or null when there is none.
nlohmann::json ReadCellRecord(const Cell& cell);
// The status a record (or null) says.
CellStatus RecordStatus(const nlohmann::json& record);

}  // namespace rvlio::experiments::ablate
