#include "rvlio/eval/associate.h"

#include <algorithm>
#include <sstream>
#include <string>

namespace rvlio {
namespace {

Status CheckOrdered(const Trajectory& trajectory, const char* name) {
  if (trajectory.empty()) return Status::InvalidInput(std::string(name) + " trajectory is empty");
  for (size_t i = 1; i < trajectory.size(); ++i)
    if (trajectory[i].t_ns < trajectory[i - 1].t_ns)
      return Status::InvalidInput(std::string(name) + " trajectory: stamp " + std::to_string(i) +
                                  " is earlier than stamp " + std::to_string(i - 1));
  return Status::Ok();
}

TimeNs AbsDiff(TimeNs a, TimeNs b) { return a > b ? a - b : b - a; }

// Index of the stamp of `sorted` nearest to t; the first one of equally near
// stamps (numpy.argmin). Binary search: O(log n).
size_t Nearest(const Trajectory& sorted, TimeNs t) {
  const auto by_time = [](const StampedPose& p, TimeNs x) { return p.t_ns < x; };
  const size_t upper = static_cast<size_t>(
      std::lower_bound(sorted.begin(), sorted.end(), t, by_time) - sorted.begin());
  size_t best = upper;
  if (upper == sorted.size() ||
      (upper > 0 && AbsDiff(sorted[upper - 1].t_ns, t) <= AbsDiff(sorted[upper].t_ns, t))) {
    // The predecessor wins ties; step back to the first of its repeated stamps.
    best = upper - 1;
    const TimeNs stamp = sorted[best].t_ns;
    best = static_cast<size_t>(
        std::lower_bound(sorted.begin(), sorted.begin() + best, stamp, by_time) - sorted.begin());
  }
  return best;
}

}  // namespace

StatusOr<Association> Associate(const Trajectory& ref, const Trajectory& est, TimeNs max_dt_ns) {
  if (Status s = CheckOrdered(ref, "reference"); !s.ok()) return s;
  if (Status s = CheckOrdered(est, "estimated"); !s.ok()) return s;
  // evo: the second trajectory (estimate) is the "longer" one only when it is
  // strictly longer.
  const bool est_longer = est.size() > ref.size();
  const Trajectory& shorter = est_longer ? ref : est;
  const Trajectory& longer = est_longer ? est : ref;
  Association a;
  for (size_t i = 0; i < shorter.size(); ++i) {
    const size_t j = Nearest(longer, shorter[i].t_ns);
    if (AbsDiff(longer[j].t_ns, shorter[i].t_ns) > max_dt_ns) continue;
    a.ref_index.push_back(est_longer ? i : j);
    a.est_index.push_back(est_longer ? j : i);
  }
  if (a.size() == 0) {
    std::ostringstream os;
    os << "no matching timestamps between reference (" << ref.size() << " poses) and estimate ("
       << est.size() << " poses) with |dt| <= " << NsToSeconds(max_dt_ns) << " s";
    return Status::InvalidInput(os.str());
  }
  return a;
}

void ApplyAssociation(const Association& association, const Trajectory& ref, const Trajectory& est,
                      Trajectory* ref_matched, Trajectory* est_matched) {
  ref_matched->clear();
  est_matched->clear();
  ref_matched->reserve(association.size());
  est_matched->reserve(association.size());
  for (size_t k = 0; k < association.size(); ++k) {
    ref_matched->push_back(ref[association.ref_index[k]]);
    est_matched->push_back(est[association.est_index[k]]);
  }
}

}  // namespace rvlio
