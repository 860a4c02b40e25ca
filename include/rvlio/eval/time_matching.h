#pragma once
// Time association of two trajectories, evo's rule (evo.core.sync,
// nearest_time): for each stamp of the SHORTER trajectory (the estimate when
// both have the same length) the nearest stamp of the longer one, the earliest
// of equally near ones; the pair is kept when |dt| <= max_dt. The association
// is not one-to-one: two stamps of the shorter trajectory may share a partner.
//
// Like evo (numpy), the time differences are computed in double seconds from
// the double nearest to each stamp (what parsing the file's decimal text
// gives), not in exact nanoseconds: near-ties such as 226.3093 / 226.31095 /
// 226.3126 (exactly 1.65 ms either side) then resolve the way evo resolves
// them, and so does the max_dt boundary.
#include <cstddef>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"

namespace rvlio {

struct Association {
  // Matched pairs in the order of the shorter trajectory.
  std::vector<size_t> ref_index;
  std::vector<size_t> est_index;
  size_t size() const { return ref_index.size(); }
};

// The double nearest to t_ns / 1e9, i.e. what strtod gives for the stamp's
// exact decimal text.
double StampSeconds(TimeNs t_ns);

// Both trajectories must have non-decreasing stamps. Error when a stamp
// decreases, a trajectory is empty, or no pair is within max_dt_s (s).
StatusOr<Association> Associate(const Trajectory& ref, const Trajectory& est, double max_dt_s);

// The matched sub-trajectories, pose k of each forming pair k.
void ApplyAssociation(const Association& association, const Trajectory& ref, const Trajectory& est,
                      Trajectory* ref_matched, Trajectory* est_matched);

}  // namespace rvlio
