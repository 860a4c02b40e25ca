#pragma once
// Batch refinement as independent chunk jobs (`rvlio refine --chunk K --of N`,
// `rvlio merge`; docs/refine.md). No I/O.
//
// Chunk spans. The initial trajectory's time span [t0, t1] is cut into N
// equal cores; chunk K (1-based) refines the scans ending inside its core
// widened by half the overlap on each side (clipped to [t0, t1]), so
// consecutive chunks share `overlap_s` seconds of scans around each border.
// The spans depend only on the initial trajectory's first and last stamps,
// N and the overlap: every job computes them alone, before reading anything.
//
// Merge. Chunk 1 gives the merged frame. Each next chunk is carried into it
// by the rigid transform that best maps its poses in the shared interval
// onto the merged poses at the same stamps (rotation: the normalized mean of
// the relative rotations; translation: the mean of the position offsets),
// then the two are blended across the shared interval (weight of the new
// chunk rising linearly from 0 at its first stamp to 1 at the previous
// chunk's last; positions interpolated, rotations slerped), so the merged
// trajectory has no step at a border. Stamps outside the shared interval
// come from the one chunk that holds them.
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// A chunk needs at least this many refined scans, and two neighbouring
// chunks at least this many shared poses to be aligned.
constexpr int kRefineJobMinScans = 10;
constexpr int kRefineJobMinSharedPoses = 3;

// The time span of chunk `chunk` of `count` (1-based), all in ns.
struct RefineJobSpan {
  int chunk = 1;  // 1-based
  int count = 1;
  TimeNs core_begin_ns = 0, core_end_ns = 0;  // the share of [t0, t1] that is this chunk's own
  TimeNs begin_ns = 0, end_ns = 0;            // the core plus half the overlap each side, clipped

  // A scan ending at t_ns belongs to the chunk.
  bool Contains(TimeNs t_ns) const { return t_ns >= begin_ns && t_ns <= end_ns; }
};

// InvalidInput (naming --chunk / --of / refine.job_overlap_s) when
// count < 1, chunk outside 1..count, t1 <= t0, overlap_s < 0, or a core
// shorter than the overlap (the shared intervals of a chunk would overlap
// each other).
StatusOr<RefineJobSpan> MakeRefineJobSpan(TimeNs t0_ns, TimeNs t1_ns, int chunk, int count,
                                          double overlap_s);

// One chunk job's refined trajectory (T_world_imu at its scans' ends, sorted).
struct RefineJobTrajectory {
  RefineJobSpan span;
  Trajectory trajectory;
};

// How one chunk was carried into the merged frame.
struct RefineJobAlignment {
  int chunk = 1;
  Pose3 T_merged_chunk;     // identity for chunk 1
  int shared_poses = 0;     // with the previous chunk (0 for chunk 1)
  double rms_residual_m = 0.0;  // position RMS over the shared poses after alignment
  double max_residual_m = 0.0;
  double max_residual_deg = 0.0;
};

struct RefineJobMerge {
  Trajectory trajectory;
  std::vector<RefineJobAlignment> alignments;  // per chunk, in order
};

// Merges the chunks (ordered 1..N, as many as their spans' count).
// InvalidInput when they are not 1..N of one N or when two neighbours share
// fewer than kRefineJobMinSharedPoses stamps (naming both chunks).
StatusOr<RefineJobMerge> MergeRefineJobs(const std::vector<RefineJobTrajectory>& chunks);

// Other trajectories of the same chunks (their trajectory_imu.tum: a pose at
// every IMU sample and scan end) merged as MergeRefineJobs merged their scan
// poses: carried by its alignments, blended across the same shared intervals
// with the same weights. Where a chunk's poses at the scan ends are those of
// its scan-rate trajectory, so are the merged ones. InvalidInput as
// MergeRefineJobs for a bad chunk set, or when the alignments are not one per chunk.
StatusOr<Trajectory> MergeAlignedTrajectories(const std::vector<RefineJobTrajectory>& chunks,
                                              const std::vector<RefineJobAlignment>& alignments);

// The pose a fraction w in [0, 1] of the way from a to b (linear position, slerp).
StampedPose BlendPoses(const StampedPose& a, const StampedPose& b, double w);

}  // namespace rvlio
