#include "rvlio/math/so3.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio {
namespace so3 {
namespace {

// Below this angle the closed-form coefficients lose digits to cancellation
// (or divide by zero); their Taylor series to theta^4 are exact to ~1e-20.
constexpr double kTaylorAngle = 1e-3;

// Coefficients of W = Hat(w) and W^2 in Exp, Jr and JrInv, theta = |w|:
//   a = sin(theta)/theta,               Exp = I + a W + b W^2
//   b = (1 - cos(theta))/theta^2,       Jr  = I - b W + c W^2
//   c = (theta - sin(theta))/theta^3,   JrInv = I + W/2 + d W^2
//   d = (1 - (theta/2) cot(theta/2))/theta^2
// b uses the half-angle form 2 sin^2(theta/2)/theta^2 (no cancellation);
// d uses cot(theta/2), which is finite at pi (unlike (1+cos)/sin forms).
struct Coefficients {
  double a, b, c, d;
};

Coefficients ComputeCoefficients(double theta) {
  const double t2 = theta * theta;
  if (theta < kTaylorAngle) {
    const double t4 = t2 * t2;
    return {1.0 - t2 / 6.0 + t4 / 120.0, 0.5 - t2 / 24.0 + t4 / 720.0,
            1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0, 1.0 / 12.0 + t2 / 720.0 + t4 / 30240.0};
  }
  const double half = 0.5 * theta;
  const double s = std::sin(theta);
  const double sh = std::sin(half);
  return {s / theta, 2.0 * sh * sh / t2, (theta - s) / (t2 * theta),
          (1.0 - half * std::cos(half) / sh) / t2};
}

}  // namespace

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const Coefficients k = ComputeCoefficients(w.norm());
  const Eigen::Matrix3d W = Hat(w);
  return Eigen::Matrix3d::Identity() + k.a * W + k.b * W * W;
}

Eigen::Vector3d Log(const Eigen::Matrix3d& R) {
  // Eigen's matrix-to-quaternion conversion branches on the largest of
  // trace / diagonal elements (Shepperd's method), which keeps every
  // component accurate near pi where the trace formula acos((tr-1)/2) fails.
  return LogQuat(Eigen::Quaterniond(R));
}

Eigen::Quaterniond ExpQuat(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  const double half = 0.5 * theta;
  // sin(theta/2)/theta, with its series below kTaylorAngle.
  const double t2 = theta * theta;
  const double s =
      theta < kTaylorAngle ? 0.5 - t2 / 48.0 + t2 * t2 / 3840.0 : std::sin(half) / theta;
  return Eigen::Quaterniond(std::cos(half), s * w.x(), s * w.y(), s * w.z());
}

Eigen::Vector3d LogQuat(const Eigen::Quaterniond& q_in) {
  // q and -q are the same rotation; pick qw >= 0 so that the angle is in [0, pi].
  const double sign = q_in.w() < 0.0 ? -1.0 : 1.0;
  const double qw = sign * q_in.w();
  const Eigen::Vector3d qv = sign * q_in.vec();
  const double n = qv.norm();
  RVLIO_CHECK_MSG(n > 0.0 || qw > 0.0, "LogQuat of a zero quaternion");
  // theta = 2 atan2(|qv|, qw); w = theta * qv / |qv|. atan2 is well conditioned
  // both near 0 (n << qw) and near pi (qw -> 0).
  if (n < 1e-8 * qw) {
    // 2 atan(x)/n with x = n/qw: 2/qw (1 - x^2/3).
    const double x2 = (n * n) / (qw * qw);
    return (2.0 / qw) * (1.0 - x2 / 3.0) * qv;
  }
  return (2.0 * std::atan2(n, qw) / n) * qv;
}

Eigen::Matrix3d Jr(const Eigen::Vector3d& w) {
  const Coefficients k = ComputeCoefficients(w.norm());
  const Eigen::Matrix3d W = Hat(w);
  return Eigen::Matrix3d::Identity() - k.b * W + k.c * W * W;
}

Eigen::Matrix3d JrInv(const Eigen::Vector3d& w) {
  const Coefficients k = ComputeCoefficients(w.norm());
  const Eigen::Matrix3d W = Hat(w);
  return Eigen::Matrix3d::Identity() + 0.5 * W + k.d * W * W;
}

Eigen::Matrix3d Jl(const Eigen::Vector3d& w) { return Jr(-w); }

Eigen::Matrix3d JlInv(const Eigen::Vector3d& w) { return JrInv(-w); }

Eigen::Matrix3d LogRightJacobian(const Eigen::Matrix3d& R) { return JrInv(Log(R)); }

Eigen::Matrix3d ExpTimesVectorJacobian(const Eigen::Vector3d& w, const Eigen::Vector3d& v) {
  return -Exp(w) * Hat(v) * Jr(w);
}

}  // namespace so3

Eigen::Vector3d RpyDeg(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::max(-1.0, std::min(1.0, -R(2, 0))));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return Eigen::Vector3d(roll, pitch, yaw) * (180.0 / M_PI);
}

}  // namespace rvlio
