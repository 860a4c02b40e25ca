#include "rvlio/refine/init.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rvlio/imu/static_init.h"
#include "rvlio/math/pose_interpolation.h"

namespace rvlio {
namespace {

std::string Seconds(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", NsToSeconds(t_ns));
  return buf;
}

// Why fewer than 2 scans can be refined.
Status TooFewScans(const RefineInput& input, const RefineStats& st, size_t kept) {
  const TimeNs init0 = input.init.front().t_ns, init1 = input.init.back().t_ns;
  const TimeNs imu0 = input.imu.front().t_ns, imu1 = input.imu.back().t_ns;
  const TimeNs scan0 = input.scans.front().t_end_ns, scan1 = input.scans.back().t_end_ns;
  std::string why = "only " + std::to_string(kept) + " of " + std::to_string(st.scans_input) +
                    " scans can be refined (need 2): ";
  if (init1 < scan0 || init0 > scan1)
    return Status::InvalidInput(why + "the initial trajectory (" + Seconds(init0) + " .. " +
                                Seconds(init1) + " s) does not overlap the scans (" +
                                Seconds(scan0) + " .. " + Seconds(scan1) + " s)");
  return Status::InvalidInput(
      why + std::to_string(st.scans_outside_init) + " outside the initial trajectory (" +
      Seconds(init0) + " .. " + Seconds(init1) + " s), " + std::to_string(st.scans_without_imu) +
      " without IMU coverage (" + Seconds(imu0) + " .. " + Seconds(imu1) + " s), " +
      std::to_string(st.scans_too_few_points) + " with fewer than " +
      std::to_string(kRefineMinScanPoints) + " points");
}

}  // namespace

Status CheckRefineInput(const RefineInput& input) {
  if (input.init.empty()) return Status::InvalidInput("the initial trajectory has no poses");
  if (input.imu.empty()) return Status::InvalidInput("no IMU samples to refine with");
  if (input.scans.empty()) return Status::InvalidInput("no scans to refine");
  return Status::Ok();
}

StatusOr<RefineSequence> SelectRefineScans(const RefineInput& input, RefineStats* stats) {
  RefineStats& st = *stats;
  st.scans_input = static_cast<int64_t>(input.scans.size());
  st.imu_samples = static_cast<int64_t>(input.imu.size());
  const TimeNs init0 = input.init.front().t_ns, init1 = input.init.back().t_ns;
  const TimeNs imu0 = input.imu.front().t_ns, imu1 = input.imu.back().t_ns;
  RefineSequence seq;
  seq.input = &input;
  for (size_t i = 0; i < input.scans.size(); ++i) {
    const Scan& s = input.scans[i];
    if (static_cast<int>(s.points.size()) < kRefineMinScanPoints) {
      ++st.scans_too_few_points;
    } else if (s.t_end_ns < init0 || s.t_end_ns > init1) {
      ++st.scans_outside_init;
    } else if (s.t_start_ns < imu0 || s.t_end_ns > imu1) {
      ++st.scans_without_imu;
    } else if (!seq.kept.empty() && s.t_end_ns <= input.scans[seq.kept.back()].t_end_ns) {
      ++st.scans_out_of_order;
    } else {
      seq.kept.push_back(static_cast<int>(i));
    }
  }
  st.scans_refined = static_cast<int64_t>(seq.kept.size());
  if (seq.kept.size() < 2) return TooFewScans(input, st, seq.kept.size());
  seq.points.resize(seq.kept.size());
  for (int k = 0; k < seq.size(); ++k) {
    const Scan& scan = seq.scan(k);
    const std::vector<LidarPoint>& from = scan.points;
    RefineScanPoints& to = seq.points[k];
    to.p_lidar.resize(from.size());
    to.t_ns.resize(from.size());
    to.intensity.resize(scan.has_intensity ? from.size() : 0);
    to.ring.resize(scan.has_ring ? from.size() : 0);
    for (size_t i = 0; i < from.size(); ++i) {
      to.p_lidar[i] = from[i].p_lidar;
      to.t_ns[i] = from[i].t_ns;
      if (scan.has_intensity) to.intensity[i] = from[i].intensity;
      if (scan.has_ring) to.ring[i] = from[i].ring;
    }
  }
  return seq;
}

void ReleaseInputPoints(RefineInput* input) {
  for (Scan& scan : input->scans) std::vector<LidarPoint>().swap(scan.points);
}

RefineGravity InitRefineGravity(const std::vector<ImuSample>& imu, const Trajectory& init,
                                const ImuOptions& options) {
  const TimeNs t0 = imu.front().t_ns;
  const TimeNs t1 = t0 + SecondsToNs(options.init_duration);
  std::vector<ImuSample> first;
  for (const ImuSample& s : imu) {
    if (s.t_ns > t1) break;
    first.push_back(s);
  }
  const StaticAlignment a = AlignStatic(first);
  RefineGravity g;
  g.started_moving = a.moving;
  if (a.moving) {
    g.g_world = Eigen::Vector3d(0.0, 0.0, -options.gravity);
    g.warning =
        "the sequence starts moving: gravity taken as (0, 0, -imu.gravity) in the initial "
        "trajectory's frame (assumed gravity-aligned, z up) and gyro bias starting at zero";
    return g;
  }
  const TimeNs t_mid = std::clamp(first.front().t_ns + (first.back().t_ns - first.front().t_ns) / 2,
                                  init.front().t_ns, init.back().t_ns);
  Pose3 T;
  InterpolatePose(init, t_mid, &T);
  const Eigen::Vector3d g_imu = a.R_world_imu.transpose() * a.g_world;
  g.g_world = T.R * g_imu;
  g.from_static = true;
  g.bg = a.gyro_bias;
  return g;
}

std::vector<RefineState> InitialRefineStates(const RefineSequence& sequence, const Trajectory& init,
                                             const Eigen::Vector3d& bg) {
  std::vector<RefineState> states(sequence.size());
  for (int k = 0; k < sequence.size(); ++k) {
    RefineState& s = states[k];
    s.t_ns = sequence.scan(k).t_end_ns;
    Pose3 T;
    InterpolatePose(init, s.t_ns, &T);
    PoseBlock(T).ToArray(s.pose.data());
    SpeedBiasBlock sb;
    sb.v_world_imu = FiniteDifferenceVelocity(init, s.t_ns, kRefineVelocityHalfWindowNs);
    sb.bg = bg;
    sb.ToArray(s.speed_bias.data());
  }
  return states;
}

Status CheckResumedStates(const std::vector<RefineState>& resumed,
                          const std::vector<RefineState>& initial) {
  if (resumed.size() != initial.size())
    return Status::InvalidInput("the resumed state has " + std::to_string(resumed.size()) +
                                " scan states, this input refines " +
                                std::to_string(initial.size()) + " scans");
  for (size_t k = 0; k < initial.size(); ++k)
    if (resumed[k].t_ns != initial[k].t_ns || !AllFinite(resumed[k]))
      return Status::InvalidInput("the resumed state of scan " + std::to_string(k) +
                                  " does not belong to this input (stamp " +
                                  Seconds(resumed[k].t_ns) + " s, expected " +
                                  Seconds(initial[k].t_ns) + " s)");
  return Status::Ok();
}

bool AllFinite(const RefineState& s) {
  for (double x : s.pose)
    if (!std::isfinite(x)) return false;
  for (double x : s.speed_bias)
    if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace rvlio
