#include "divergence_cli.h"

#include <cmath>
#include <cstdio>

namespace rvlio::cli {

void WarnDivergence(const std::string& command, const DivergenceReport& r, size_t* printed) {
  for (; *printed < r.events.size(); ++*printed) {
    const DivergenceEvent& e = r.events[*printed];
    std::fprintf(stderr, "rvlio %s: warning: %s at bag time %.3f s: %s\n", command.c_str(),
                 e.lost ? "divergence" : "inconsistency", NsToSeconds(e.t_ns),
                 e.Describe().c_str());
  }
}

// When the residuals grew with the motion before the divergence: the likely
// cause and the command that checks it.
static std::string ClockHint(const DivergenceReport& r) {
  if (!r.clock_suspect) return "";
  char text[512];
  if (std::isfinite(r.clock_offset_s)) {
    std::snprintf(text, sizeof(text),
                  "; before it the scans' rotation against the gyro looked like a LiDAR-IMU "
                  "clock offset of %+.1f ms: check the clocks with `rvlio calibrate-time --bag "
                  "RECORDING --config CONFIG` and set lidar.time_offset, or run with --set "
                  "lidar.estimate_time_offset=true",
                  1e3 * r.clock_offset_s);
    return text;
  }
  std::snprintf(text, sizeof(text),
                "; the point-to-plane residuals grew with the motion before it (%.3f m median "
                "at rest, %.3f m moving), as unsynchronized LiDAR and IMU clocks make them (or "
                "wrong extrinsics): check the clocks with `rvlio calibrate-time --bag RECORDING "
                "--config CONFIG` and set lidar.time_offset, or run with --set "
                "lidar.estimate_time_offset=true",
                r.residual_at_rest_m, r.residual_moving_m);
  return text;
}

static int64_t LostEpisodes(const DivergenceReport& r) {
  int64_t n = 0;
  for (int64_t e : r.episodes) n += e;
  return n;
}

// With a reference map, a divergence that began while the gyro showed no
// rotation: the start or the map.
static std::string StartHint(const DivergenceReport& r, bool reference_map) {
  for (const DivergenceEvent& e : r.events) {
    if (!e.lost) continue;
    if (!reference_map || !e.still) return "";
    return "; it began while the gyro showed no rotation, where neither a wrong extrinsic "
           "rotation nor unsynchronized clocks show, "
           "with the scans localized in the reference map: the start pose (--initial-pose) or the "
           "map (--map) is wrong";
  }
  return "";
}

int FinishDiverged(const std::string& command, const DivergenceReport& r,
                   const std::string& out_dir, bool allow, bool reference_map) {
  char when[64];
  std::snprintf(when, sizeof(when), "%.3f", NsToSeconds(r.first_t_ns));
  const std::string what = "the estimate diverged from bag time " + std::string(when) + " s (" +
                           std::to_string(LostEpisodes(r)) + " episode(s), " +
                           std::to_string(r.scans_flagged) +
                           " scans flagged; see divergence in summary.json); outputs written to " +
                           out_dir + " for inspection" + StartHint(r, reference_map) + ClockHint(r);
  if (allow) {
    std::fprintf(stderr, "rvlio %s: warning: %s\n", command.c_str(), what.c_str());
    return 0;
  }
  return Fail(command, what + "; --allow-divergence to exit 0", kExitDiverged);
}

}  // namespace rvlio::cli
