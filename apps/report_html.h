#pragma once
// report.html: the page template (apps/report/report.html with report.css and
// report.js) and three.js, compiled into the tool (CMake embeds them from the
// source tree and from libjs-three, docs/report.md), filled with the model of
// rvlio/experiments/report_data.h. The page needs nothing else: no network, no files.
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/experiments/report_data.h"

namespace rvlio::cli::report {

using experiments::report::ReportOptions;

// The whole page for `model` (experiments::report::BuildReport).
std::string RenderReportHtml(const experiments::report::ReportModel& model);

// Builds the model of `dir` and writes its page atomically to `out_path`
// ("" = DIR/report.html). Returns the path written and its size in bytes.
struct WrittenReport {
  std::string path;
  size_t bytes = 0;
};
StatusOr<WrittenReport> WriteReport(const std::string& dir, const std::string& out_path,
                                    const ReportOptions& options);

}  // namespace rvlio::cli::report
