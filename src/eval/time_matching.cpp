#include "rvlio/eval/time_matching.h"

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
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

std::vector<double> Seconds(const Trajectory& trajectory) {
  std::vector<double> s(trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) s[i] = StampSeconds(trajectory[i].t_ns);
  return s;
}

// numpy.argmin(|sorted - t|): the nearest stamp, the first of equally near
// ones. The rounded differences are still unimodal along a sorted array, so
// the minimum sits next to the insertion point: binary search, O(log n).
size_t Nearest(const std::vector<double>& sorted, double t) {
  const auto diff = [&](size_t j) { return std::fabs(sorted[j] - t); };
  const size_t upper =
      static_cast<size_t>(std::lower_bound(sorted.begin(), sorted.end(), t) - sorted.begin());
  size_t best = upper;
  if (upper == sorted.size() || (upper > 0 && diff(upper - 1) <= diff(upper))) best = upper - 1;
  while (best > 0 && diff(best - 1) <= diff(best)) --best;  // first of equal differences
  return best;
}

}  // namespace

double StampSeconds(TimeNs t_ns) {
  const uint64_t magnitude =
      t_ns < 0 ? 0 - static_cast<uint64_t>(t_ns) : static_cast<uint64_t>(t_ns);
  char text[48];
  std::snprintf(text, sizeof(text), "%s%" PRIu64 ".%09" PRIu64, t_ns < 0 ? "-" : "",
                magnitude / uint64_t{1000000000}, magnitude % uint64_t{1000000000});
  return std::strtod(text, nullptr);  // correctly rounded, as numpy's parser
}

StatusOr<Association> Associate(const Trajectory& ref, const Trajectory& est, double max_dt_s) {
  if (Status s = CheckOrdered(ref, "reference"); !s.ok()) return s;
  if (Status s = CheckOrdered(est, "estimated"); !s.ok()) return s;
  // evo: the second trajectory (estimate) is the longer one only when it is
  // strictly longer.
  const bool est_longer = est.size() > ref.size();
  const std::vector<double> shorter = Seconds(est_longer ? ref : est);
  const std::vector<double> longer = Seconds(est_longer ? est : ref);
  Association a;
  for (size_t i = 0; i < shorter.size(); ++i) {
    const size_t j = Nearest(longer, shorter[i]);
    if (!(std::fabs(longer[j] - shorter[i]) <= max_dt_s)) continue;
    a.ref_index.push_back(est_longer ? i : j);
    a.est_index.push_back(est_longer ? j : i);
  }
  if (a.size() == 0) {
    std::ostringstream os;
    os << "no matching timestamps between reference (" << ref.size() << " poses) and estimate ("
       << est.size() << " poses) with |dt| <= " << max_dt_s << " s";
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
