#pragma once
// Time association of two trajectories, evo's rule (evo.core.sync,
// nearest_time): for each stamp of the SHORTER trajectory (the estimate when
// both have the same length) the nearest stamp of the longer one, the earliest
// of equally near ones; the pair is kept when |dt| <= max_dt. The association
// is not one-to-one: two stamps of the shorter trajectory may share a partner.
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

// Both trajectories must have non-decreasing stamps. Error when a stamp
// decreases, a trajectory is empty, or no pair is within max_dt_ns.
StatusOr<Association> Associate(const Trajectory& ref, const Trajectory& est, TimeNs max_dt_ns);

// The matched sub-trajectories, pose k of each forming pair k.
void ApplyAssociation(const Association& association, const Trajectory& ref, const Trajectory& est,
                      Trajectory* ref_matched, Trajectory* est_matched);

}  // namespace rvlio
