#pragma once
// The report's model as JSON (report_data.cpp), for BuildReport and the
// tests; private to the library.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rvlio/experiments/report_data.h"

namespace rvlio::experiments::report {

// The columns of a metrics table from JSON rows: the given leading keys, then
// every number or boolean at the top level of any row, then those of nested
// objects one level down as "parent.key" (skipping the `skip` objects), in the
// order they first appear. Map metrics added to compare.json or cell.json thus
// appear without a change here.
std::vector<std::string> MetricColumns(const std::vector<nlohmann::json>& rows,
                                       const std::vector<std::string>& leading,
                                       const std::vector<std::string>& skip);
// The value of a "parent.key" or "key" column in `row` (null when absent).
nlohmann::json ColumnValue(const nlohmann::json& row, const std::string& column);

// The whole model for `dir` (DetectFolderKind first). InvalidInput when the
// folder holds nothing reportable or a file it names cannot be read.
StatusOr<nlohmann::json> BuildReportModel(const std::string& dir, const ReportOptions& options);

}  // namespace rvlio::experiments::report
