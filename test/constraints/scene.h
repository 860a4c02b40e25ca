#pragma once
// Tiny ray-casting scenes for the association tests: an axis-aligned box room
// seen from inside, and a 32-beam spinning LiDAR (ring pattern).
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Core>

namespace rvlio {
namespace test {

// Unit ray directions of a spinning LiDAR in its own frame, ring-major
// (all columns of beam 0, then beam 1, ...) like an Ouster cloud.
inline std::vector<Eigen::Vector3d> RingDirections(int beams, double min_elev_deg,
                                                   double max_elev_deg, int columns) {
  std::vector<Eigen::Vector3d> dirs;
  for (int b = 0; b < beams; ++b) {
    const double e = (min_elev_deg + (max_elev_deg - min_elev_deg) * b / (beams - 1)) * M_PI / 180;
    for (int c = 0; c < columns; ++c) {
      const double a = 2 * M_PI * c / columns;
      dirs.emplace_back(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
    }
  }
  return dirs;
}

// Axis-aligned box [lo, hi] seen from an interior point.
struct BoxRoom {
  Eigen::Vector3d lo, hi;

  // Range to the first face hit from interior point o along unit dir.
  double Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& dir) const {
    double t = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (dir(a) > 1e-12) t = std::min(t, (hi(a) - o(a)) / dir(a));
      if (dir(a) < -1e-12) t = std::min(t, (lo(a) - o(a)) / dir(a));
    }
    return t;
  }

  // Inward unit normal of the face nearest to p (a point on the surface).
  Eigen::Vector3d InwardNormal(const Eigen::Vector3d& p) const {
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      if (std::abs(p(a) - lo(a)) < best) {
        best = std::abs(p(a) - lo(a));
        n.setZero();
        n(a) = 1;
      }
      if (std::abs(p(a) - hi(a)) < best) {
        best = std::abs(p(a) - hi(a));
        n.setZero();
        n(a) = -1;
      }
    }
    return n;
  }

  // Distance from p (on the surface) to the nearest edge of its face.
  double DistanceToEdge(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d n = InwardNormal(p);
    double d = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (n(a) != 0) continue;
      d = std::min({d, p(a) - lo(a), hi(a) - p(a)});
    }
    return d;
  }

  // Jittered grid samples of every face, spacing s (m).
  std::vector<Eigen::Vector3d> SampleSurface(double s, std::mt19937* rng) const {
    std::uniform_real_distribution<double> jitter(-0.3 * s, 0.3 * s);
    std::vector<Eigen::Vector3d> pts;
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (double u = lo(b) + s / 2; u < hi(b); u += s) {
        for (double v = lo(c) + s / 2; v < hi(c); v += s) {
          for (double w : {lo(a), hi(a)}) {
            Eigen::Vector3d p;
            p(a) = w;
            p(b) = u + jitter(*rng);
            p(c) = v + jitter(*rng);
            pts.push_back(p);
          }
        }
      }
    }
    return pts;
  }
};

}  // namespace test
}  // namespace rvlio
