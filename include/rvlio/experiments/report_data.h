#pragma once
// The data of `rvlio report` (docs/report.md, target rvlio::experiments):
// what a compare, demo, ablate or run folder holds, gathered into one JSON
// model that report.html draws.
// Arrays travel as base64 of little-endian float32 (ReportArray), so a 100 s
// run stays compact; the map is thinned by a stride to at most
// ReportOptions::max_points points and the page says so.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio::experiments::report {

enum class FolderKind { kCompare, kDemo, kAblate, kRun };
const char* FolderKindName(FolderKind kind);

// compare.json -> compare (demo when a data/ folder with the simulation sits
// next to it), plan.json + cells/ -> ablate, summary.json + trajectory.tum ->
// run. InvalidInput naming the folder when it is missing or holds none.
StatusOr<FolderKind> DetectFolderKind(const std::string& dir);

struct ReportOptions {
  std::string gt;                // ground truth for a run folder (compare/ablate name their own)
  size_t max_points = 1000000;   // map points embedded at most (stride thinning above)
  size_t max_runs = 12;          // trajectories drawn at most (ablate grids can be large)
};

// base64 of the values as little-endian float32 (the page decodes it into a
// Float32Array).
std::string ReportArray(const std::vector<float>& values);

// Every stride-th point so that at most max_points remain (stride 1 keeps all).
size_t ThinningStride(size_t points, size_t max_points);

// The model of a folder's page: its title and the JSON text report.html
// embeds (runs, table, ground truth, map cloud, control points, notes).
struct ReportModel {
  FolderKind kind = FolderKind::kRun;
  std::string title;
  std::string json;
};

// The whole model for `dir` (DetectFolderKind first). InvalidInput when the
// folder holds nothing reportable or a file it names cannot be read.
StatusOr<ReportModel> BuildReport(const std::string& dir, const ReportOptions& options);

}  // namespace rvlio::experiments::report
