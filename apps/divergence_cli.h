#pragma once
// How the commands report the divergence monitor (odometry/divergence.h):
// one warning line per episode while running, a `divergence` object in
// summary.json, and exit status kExitDiverged unless --allow-divergence
// (common_options.h). DivergenceJson is in rvlio/outputs/summary_json.h.
#include <cstddef>
#include <string>

#include "cli.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/odometry/divergence.h"

namespace rvlio::cli {

// "Ran to the end but diverged": every output is written for inspection.
constexpr int kExitDiverged = 3;

// Prints "rvlio CMD: warning: divergence at bag time T s: WHAT" (or
// "inconsistency at" for an episode a clock offset explains) for every
// episode start after the first *printed ones; updates *printed.
void WarnDivergence(const std::string& command, const DivergenceReport& report, size_t* printed);

// The closing line of a diverged run; returns kExitDiverged, or 0 when
// allowed (the line is then a warning). reference_map: the run localized in
// one (`run --map`); a divergence from rest then names the start and the map.
int FinishDiverged(const std::string& command, const DivergenceReport& report,
                   const std::string& out_dir, bool allow, bool reference_map = false);

}  // namespace rvlio::cli
