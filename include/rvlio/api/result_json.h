#pragma once
// The JSON the command writes of the API's typed results (`rvlio eval
// --json`, summary.json "chunks"). Private to the I/O layer, the command
// and Python: the public API (rvlio/api.h) carries no JSON type.
#include <functional>

#include <nlohmann/json.hpp>

#include "rvlio/api.h"

namespace rvlio {

// `rvlio eval --json`: matched, align, scale, ape, ape_rot_deg, rpe,
// rpe_rot_deg, end_point_error, along_axis, warnings (10 significant digits).
nlohmann::json EvalJson(const EvalResult& result);

// `rvlio eval --degeneracy --json`.
nlohmann::json DegeneracyEvalJson(const DegeneracyEvalResult& result);

// `rvlio eval --map --json`: map_points, ref_points, max_distance, inliers,
// no_plane, outlier_fraction, accuracy and nearest {count, mean, rms, median,
// p95, max}, completeness, chamfer, chamfer_definition, axis {origin,
// direction}, profile [{chainage, map_points, map_with_plane, rms, median,
// p95, ref_points, completeness}] (10 significant digits; null for NaN).
nlohmann::json MapEvalJson(const MapEvalResult& result);

// summary.json's entry of one merged chunk (MergeResult::chunks).
nlohmann::json MergedChunkJson(const MergedChunk& chunk);

// RunRecording with `annotate` called on summary.json before it is
// serialized and written (`rvlio live` adds its figures); null: RunRecording.
using SummaryAnnotator = std::function<void(nlohmann::json* summary)>;
StatusOr<RunResult> RunRecordingAnnotated(const RunArgs& args, const SummaryAnnotator& annotate);

}  // namespace rvlio
