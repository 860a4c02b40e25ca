#include "rvlio/refine/jobs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "rvlio/common/text.h"
#include "rvlio/math/pose_interpolation.h"

namespace rvlio {
namespace {

Pose3 ToPose(const StampedPose& p) { return Pose3(p.q_world_imu, p.p_world_imu); }

StampedPose Apply(const Pose3& T, const StampedPose& p) {
  StampedPose out = p;
  out.p_world_imu = T * p.p_world_imu;
  out.q_world_imu = Eigen::Quaterniond(T.R * p.q_world_imu.normalized().toRotationMatrix());
  out.q_world_imu.normalize();
  return out;
}

// The pairs (merged pose, chunk pose) at the stamps both hold inside the
// chunk's shared interval with the merged trajectory so far.
struct SharedPoses {
  std::vector<StampedPose> merged, chunk;
};

SharedPoses FindShared(const std::map<TimeNs, StampedPose>& merged, const Trajectory& chunk,
                       TimeNs shared_end_ns) {
  SharedPoses s;
  for (const StampedPose& p : chunk) {
    if (p.t_ns > shared_end_ns) break;
    auto it = merged.find(p.t_ns);
    if (it == merged.end()) continue;
    s.merged.push_back(it->second);
    s.chunk.push_back(p);
  }
  return s;
}

// T_merged_chunk from the shared poses: normalized mean of R_m R_c^T (signs
// aligned), then the mean of p_m - R p_c.
Pose3 AlignShared(const SharedPoses& s) {
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  Eigen::Quaterniond first = Eigen::Quaterniond::Identity();  // set at i = 0
  for (size_t i = 0; i < s.merged.size(); ++i) {
    Eigen::Quaterniond q = s.merged[i].q_world_imu.normalized() * s.chunk[i].q_world_imu.normalized().conjugate();
    if (i == 0) first = q;
    if (q.coeffs().dot(first.coeffs()) < 0.0) q.coeffs() = -q.coeffs();
    sum += q.coeffs();
  }
  Eigen::Quaterniond q_mean;
  q_mean.coeffs() = sum.normalized();
  Pose3 T(q_mean, Eigen::Vector3d::Zero());
  Eigen::Vector3d t_sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < s.merged.size(); ++i)
    t_sum += s.merged[i].p_world_imu - T.R * s.chunk[i].p_world_imu;
  T.t = t_sum / static_cast<double>(s.merged.size());
  return T;
}

void Residuals(const SharedPoses& s, const Pose3& T, RefineJobAlignment* a) {
  double sum_sq = 0.0;
  for (size_t i = 0; i < s.merged.size(); ++i) {
    const Pose3 m = ToPose(s.merged[i]), c = T * ToPose(s.chunk[i]);
    const double d = (m.t - c.t).norm();
    sum_sq += d * d;
    a->max_residual_m = std::max(a->max_residual_m, d);
    const double deg =
        Eigen::AngleAxisd(m.R.transpose() * c.R).angle() * 180.0 / 3.14159265358979323846;
    a->max_residual_deg = std::max(a->max_residual_deg, deg);
  }
  a->rms_residual_m = std::sqrt(sum_sq / static_cast<double>(s.merged.size()));
}

// The chunk's poses carried into the merged frame by T_merged_chunk: at a
// stamp the merged trajectory holds inside [shared_begin, shared_end] the two
// blended (the chunk's weight rising linearly over the interval), elsewhere
// the chunk's.
void BlendInto(const Trajectory& chunk, const Pose3& T_merged_chunk, TimeNs shared_begin,
               TimeNs shared_end, std::map<TimeNs, StampedPose>* merged) {
  const double width = static_cast<double>(std::max<TimeNs>(1, shared_end - shared_begin));
  for (const StampedPose& p : chunk) {
    const StampedPose aligned = Apply(T_merged_chunk, p);
    auto it = merged->find(p.t_ns);
    if (it == merged->end() || p.t_ns > shared_end) {
      (*merged)[p.t_ns] = aligned;
      continue;
    }
    const double w = std::clamp(static_cast<double>(p.t_ns - shared_begin) / width, 0.0, 1.0);
    it->second = BlendPoses(it->second, aligned, w);
  }
}

Trajectory Values(const std::map<TimeNs, StampedPose>& merged) {
  Trajectory out;
  out.reserve(merged.size());
  for (const auto& [t_ns, p] : merged) out.push_back(p);
  return out;
}

Status CheckChunkSet(const std::vector<RefineJobTrajectory>& chunks) {
  if (chunks.empty()) return Status::InvalidInput("no chunks to merge");
  const int n = chunks.front().span.count;
  if (static_cast<int>(chunks.size()) != n)
    return Status::InvalidInput(std::to_string(chunks.size()) + " chunks given for --of " +
                                std::to_string(n));
  for (int k = 0; k < n; ++k) {
    const RefineJobSpan& s = chunks[k].span;
    if (s.count != n || s.chunk != k + 1)
      return Status::InvalidInput("chunk " + std::to_string(k + 1) + " of " + std::to_string(n) +
                                  " expected in position " + std::to_string(k + 1) + ", found " +
                                  std::to_string(s.chunk) + " of " + std::to_string(s.count));
    if (chunks[k].trajectory.empty())
      return Status::InvalidInput("chunk " + std::to_string(k + 1) + " has no poses");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<RefineJobSpan> MakeRefineJobSpan(TimeNs t0_ns, TimeNs t1_ns, int chunk, int count,
                                          double overlap_s) {
  if (count < 1) return Status::InvalidInput("--of " + std::to_string(count) + ": needs at least 1 chunk");
  if (chunk < 1 || chunk > count)
    return Status::InvalidInput("--chunk " + std::to_string(chunk) + ": chunks are numbered 1.." +
                                std::to_string(count));
  if (t1_ns <= t0_ns)
    return Status::InvalidInput("the initial trajectory spans no time: it cannot be cut into chunks");
  if (!(overlap_s >= 0.0))
    return Status::InvalidInput("refine.job_overlap_s must be >= 0");
  const double length_s = NsToSeconds(t1_ns - t0_ns);
  const double core_s = length_s / count;
  if (count > 1 && core_s < overlap_s)
    return Status::InvalidInput("--of " + std::to_string(count) + ": chunks of " +
                                FormatFixed(core_s, 3) + " s (" + FormatFixed(length_s, 3) +
                                " s of initial trajectory) are shorter than their overlap "
                                "refine.job_overlap_s = " +
                                FormatFixed(overlap_s, 3) +
                                " s; use fewer chunks or a "
                                "shorter overlap");
  RefineJobSpan s;
  s.chunk = chunk;
  s.count = count;
  const auto at = [&](int k) {  // border k of 0..count, exact at both ends
    return k == count ? t1_ns
                      : t0_ns + static_cast<TimeNs>(std::llround(
                                    static_cast<double>(t1_ns - t0_ns) * k / count));
  };
  s.core_begin_ns = at(chunk - 1);
  s.core_end_ns = at(chunk);
  const TimeNs half_ns = SecondsToNs(overlap_s / 2.0);
  s.begin_ns = chunk == 1 ? t0_ns : std::max(t0_ns, s.core_begin_ns - half_ns);
  s.end_ns = chunk == count ? t1_ns : std::min(t1_ns, s.core_end_ns + half_ns);
  return s;
}

StampedPose BlendPoses(const StampedPose& a, const StampedPose& b, double w) {
  StampedPose out = InterpolateBetween(a, b, w);
  out.q_world_imu.normalize();
  return out;
}

StatusOr<RefineJobMerge> MergeRefineJobs(const std::vector<RefineJobTrajectory>& chunks) {
  if (Status s = CheckChunkSet(chunks); !s.ok()) return s;
  RefineJobMerge out;
  std::map<TimeNs, StampedPose> merged;
  for (const StampedPose& p : chunks.front().trajectory) merged[p.t_ns] = p;
  out.alignments.push_back(RefineJobAlignment{});
  for (size_t k = 1; k < chunks.size(); ++k) {
    const TimeNs shared_begin = chunks[k].span.begin_ns;
    const TimeNs shared_end = std::min(chunks[k - 1].span.end_ns, merged.rbegin()->first);
    const SharedPoses shared = FindShared(merged, chunks[k].trajectory, shared_end);
    if (static_cast<int>(shared.merged.size()) < kRefineJobMinSharedPoses)
      return Status::InvalidInput(
          "chunks " + std::to_string(k) + " and " + std::to_string(k + 1) + " share " +
          std::to_string(shared.merged.size()) + " poses (need " +
          std::to_string(kRefineJobMinSharedPoses) + "): a longer refine.job_overlap_s");
    RefineJobAlignment a;
    a.chunk = static_cast<int>(k) + 1;
    a.T_merged_chunk = AlignShared(shared);
    a.shared_poses = static_cast<int>(shared.merged.size());
    Residuals(shared, a.T_merged_chunk, &a);
    BlendInto(chunks[k].trajectory, a.T_merged_chunk, shared_begin, shared_end, &merged);
    out.alignments.push_back(a);
  }
  out.trajectory = Values(merged);
  return out;
}

StatusOr<Trajectory> MergeAlignedTrajectories(const std::vector<RefineJobTrajectory>& chunks,
                                              const std::vector<RefineJobAlignment>& alignments) {
  if (Status s = CheckChunkSet(chunks); !s.ok()) return s;
  if (alignments.size() != chunks.size())
    return Status::InvalidInput(std::to_string(alignments.size()) + " alignments for " +
                                std::to_string(chunks.size()) + " chunks");
  std::map<TimeNs, StampedPose> merged;
  for (const StampedPose& p : chunks.front().trajectory) merged[p.t_ns] = p;
  for (size_t k = 1; k < chunks.size(); ++k) {
    const TimeNs shared_end = std::min(chunks[k - 1].span.end_ns, merged.rbegin()->first);
    BlendInto(chunks[k].trajectory, alignments[k].T_merged_chunk, chunks[k].span.begin_ns,
              shared_end, &merged);
  }
  return Values(merged);
}

}  // namespace rvlio
