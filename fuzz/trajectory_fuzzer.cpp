// libFuzzer target: TUM and KITTI trajectory parsing (formats/trajectory_io.h), the
// text parsers the file readers (ReadTum, ReadKitti, ReadTrajectory) use.
//
// Input layout (FuzzedDataProvider; fuzz/make_seeds.py writes the same): from
// the END, the mode (0 TUM, 1 KITTI at a rate, 2 KITTI with a times text,
// 3 detected format) and, for modes 1 and 3, a rate pick (uint8: < 4 a
// fuzzed double, 4 and 5 tiny rates, else pick / 8 Hz); from the FRONT, for mode 2, the times text
// (ConsumeRandomLengthString); the trajectory text is what remains.
//
// Invariants: failures are InvalidInput with a message; a parsed trajectory
// is non-empty, finite, has unit quaternions and non-decreasing stamps; written
// back as TUM lines (FormatTumLine) and as KITTI lines + times text, it parses
// again to the same trajectory (exact stamps, positions to the printed
// precision, rotations to 1e-9).
#include <fuzzer/FuzzedDataProvider.h>

#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "rvlio/formats/trajectory_io.h"

namespace {

using rvlio::StatusOr;
using rvlio::Trajectory;

[[noreturn]] void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "trajectory fuzzer invariant violated: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void CheckTrajectory(const Trajectory& trajectory) {
  if (trajectory.empty()) Fail("parsed an empty trajectory", "");
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const rvlio::StampedPose& pose = trajectory[i];
    if (!pose.p_world_imu.allFinite() || !pose.q_world_imu.coeffs().allFinite())
      Fail("non-finite pose", rvlio::FormatTumLine(pose));
    if (std::abs(pose.q_world_imu.norm() - 1.0) > 1e-9)
      Fail("quaternion not unit", rvlio::FormatTumLine(pose));
    if (i > 0 && pose.t_ns < trajectory[i - 1].t_ns) Fail("stamps decrease", "");
  }
}

// Seconds with 9 decimals, exactly the ns value.
std::string FormatStamp(int64_t t_ns) {
  const bool negative = t_ns < 0;
  const uint64_t m = negative ? 0 - static_cast<uint64_t>(t_ns) : static_cast<uint64_t>(t_ns);
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%s%" PRIu64 ".%09" PRIu64, negative ? "-" : "",
                m / 1000000000u, m % 1000000000u);
  return buf;
}

std::string FormatKittiLine(const rvlio::StampedPose& pose) {
  const Eigen::Matrix3d R = pose.q_world_imu.toRotationMatrix();
  const Eigen::Vector3d& p = pose.p_world_imu;
  std::string line;
  char buf[400];
  for (int r = 0; r < 3; ++r) {
    std::snprintf(buf, sizeof(buf), "%.17g %.17g %.17g %.17g%s", R(r, 0), R(r, 1), R(r, 2), p(r),
                  r < 2 ? " " : "\n");
    line += buf;
  }
  return line;
}

// Same stamps, positions within what `pos_decimals` printing keeps.
void RequireSame(const Trajectory& a, const Trajectory& b, double pos_abs_tol,
                 const char* what) {
  if (a.size() != b.size()) Fail(what, "pose count differs");
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d dp = a[i].p_world_imu - b[i].p_world_imu;
    const double p_tol = pos_abs_tol + 1e-15 * a[i].p_world_imu.cwiseAbs().maxCoeff();
    const double q_diff = std::min((a[i].q_world_imu.coeffs() - b[i].q_world_imu.coeffs()).norm(),
                                   (a[i].q_world_imu.coeffs() + b[i].q_world_imu.coeffs()).norm());
    if (a[i].t_ns != b[i].t_ns || dp.cwiseAbs().maxCoeff() > p_tol || q_diff > 1e-9)
      Fail(what, rvlio::FormatTumLine(a[i]) + rvlio::FormatTumLine(b[i]));
  }
}

void CheckRoundTrips(const Trajectory& trajectory) {
  std::string tum, kitti, times;
  for (const auto& pose : trajectory) {
    tum += rvlio::FormatTumLine(pose);
    kitti += FormatKittiLine(pose);
    times += FormatStamp(pose.t_ns) + "\n";
  }
  const StatusOr<Trajectory> from_tum = rvlio::ParseTumText(tum, "written.tum");
  if (!from_tum.ok()) Fail("written TUM does not parse", from_tum.status().message() + "\n" + tum);
  RequireSame(trajectory, *from_tum, 1e-9, "TUM round trip changed a pose");
  const StatusOr<Trajectory> from_kitti =
      rvlio::ParseKittiText(kitti, "written.txt", times, "times.txt");
  if (!from_kitti.ok())
    Fail("written KITTI does not parse", from_kitti.status().message() + "\n" + kitti);
  RequireSame(trajectory, *from_kitti, 0.0, "KITTI round trip changed a pose");
}

double ConsumeRate(FuzzedDataProvider& fdp) {
  const uint8_t pick = fdp.ConsumeIntegral<uint8_t>();
  if (pick < 4) return fdp.ConsumeFloatingPoint<double>();
  if (pick == 4) return std::numeric_limits<double>::min();
  if (pick == 5) return 1e-9;
  return pick / 8.0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider fdp(data, size);
  const int mode = fdp.ConsumeIntegralInRange<int>(0, 3);
  StatusOr<Trajectory> parsed = rvlio::Status::InvalidInput("unset");
  if (mode == 0) {
    parsed = rvlio::ParseTumText(fdp.ConsumeRemainingBytesAsString(), "fuzz.tum");
  } else if (mode == 1) {
    const double rate_hz = ConsumeRate(fdp);
    parsed = rvlio::ParseKittiText(fdp.ConsumeRemainingBytesAsString(), "fuzz.txt", rate_hz);
  } else if (mode == 2) {
    const std::string times = fdp.ConsumeRandomLengthString(4096);
    parsed = rvlio::ParseKittiText(fdp.ConsumeRemainingBytesAsString(), "fuzz.txt", times,
                                   "times.txt");
  } else {
    const double rate_hz = ConsumeRate(fdp);
    parsed = rvlio::ParseTrajectoryText(fdp.ConsumeRemainingBytesAsString(), "fuzz.txt", rate_hz);
  }
#ifdef RVLIO_FUZZ_VERBOSE  // seed checks: what an input parses to
  std::fprintf(stderr, "mode %d: %s %zu poses\n", mode,
               parsed.ok() ? "ok" : parsed.status().message().c_str(),
               parsed.ok() ? parsed->size() : 0);
#endif
  if (!parsed.ok()) {
    if (parsed.status().code() != rvlio::StatusCode::kInvalidInput ||
        parsed.status().message().empty())
      Fail("a failure is not InvalidInput with a message", parsed.status().message());
    return 0;
  }
  CheckTrajectory(*parsed);
  CheckRoundTrips(*parsed);
  return 0;
}
