// Ray intersection of the simulator's shapes against brute-force marching,
// height-field derivatives against finite differences, and the bucketed ray
// caster against testing every shape.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "rvlio/sim/geometry.h"
#include "rvlio/sim/presets.h"
#include "rvlio/sim/random.h"
#include "rvlio/sim/simulator.h"
#include "rvlio/sim/world.h"

namespace rvlio::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::Vector3d RandomUnit(Rng& rng) {
  Eigen::Vector3d d(rng.Normal(), rng.Normal(), rng.Normal());
  return d.normalized();
}

TEST(Random, SameSeedSameSequenceAndStreamsDiffer) {
  Rng a(42), b(42);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.Normal(), b.Normal());
  Rng s1 = Rng::Stream(42, 1), s2 = Rng::Stream(42, 2);
  EXPECT_NE(s1.NextU64(), s2.NextU64());
  // Normal(): mean 0, variance 1 within sampling error.
  Rng r(7);
  double m = 0, q = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = r.Normal();
    m += x;
    q += x * x;
  }
  EXPECT_NEAR(m / n, 0.0, 0.01);
  EXPECT_NEAR(q / n, 1.0, 0.01);
}

TEST(HeightField, MatchesLibmAndItsGradientMatchesFiniteDifferences) {
  Rng rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const HeightField hf = HeightField::Random(rng, 4, 0.04, 0.8, 4.0);
    EXPECT_NEAR(hf.amplitude_bound(), 0.04, 1e-12);
    for (int i = 0; i < 50; ++i) {
      const double u = rng.Uniform(-2000.0, 2000.0), v = rng.Uniform(-50.0, 50.0);
      double ref = 0.0;
      for (const auto& w : hf.waves()) ref += w.amplitude * std::sin(w.ku * u + w.kv * v + w.phase);
      double hu = 0, hv = 0;
      const double h = hf.Height(u, v, &hu, &hv);
      EXPECT_NEAR(h, ref, 1e-14);
      EXPECT_NEAR(hf.Height(u, v), h, 1e-15);
      EXPECT_LE(std::abs(h), hf.amplitude_bound() + 1e-15);
      EXPECT_LE(std::hypot(hu, hv), hf.slope_bound() + 1e-15);
      const double e = 1e-5;
      EXPECT_NEAR(hu, (hf.Height(u + e, v) - hf.Height(u - e, v)) / (2 * e), 1e-8);
      EXPECT_NEAR(hv, (hf.Height(u, v + e) - hf.Height(u, v - e)) / (2 * e), 1e-8);
    }
  }
}

// Raised-cosine bumps (deformations) on top of the waves: value, gradient
// and the bounds the ray caster relies on.
TEST(HeightField, BumpsAreRaisedCosinesWithinTheirBounds) {
  Rng rng(5);
  HeightField hf = HeightField::Random(rng, 3, 0.02, 0.8, 4.0);
  hf.AddBump({0.05, 1.0, 4.0, -2.0, 0.0});   // uniform in v
  hf.AddBump({-0.08, -3.0, 2.0, 1.0, 1.5});  // a patch
  EXPECT_NEAR(hf.amplitude_bound(), 0.02 + 0.05 + 0.08, 1e-12);
  EXPECT_FALSE(hf.flat());
  HeightField waves_only = HeightField(hf.waves());
  // At the first bump's centre, any v: +5 cm; at half its half-length: 2.5 cm.
  EXPECT_NEAR(hf.Height(1.0, 17.0) - waves_only.Height(1.0, 17.0), 0.05, 1e-15);
  EXPECT_NEAR(hf.Height(2.0, 17.0) - waves_only.Height(2.0, 17.0), 0.025, 1e-15);
  EXPECT_EQ(hf.Height(3.0, 17.0), waves_only.Height(3.0, 17.0));
  EXPECT_NEAR(hf.Height(-3.0, 1.0) - waves_only.Height(-3.0, 1.0), -0.08, 1e-15);
  double max_slope = 0.0, max_curv = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const double u = rng.Uniform(-6.0, 6.0), v = rng.Uniform(-3.0, 3.0);
    double hu = 0, hv = 0;
    const double h = hf.Height(u, v, &hu, &hv);
    EXPECT_NEAR(hf.Height(u, v), h, 1e-15);
    EXPECT_LE(std::abs(h), hf.amplitude_bound() + 1e-15);
    max_slope = std::max(max_slope, std::hypot(hu, hv));
    const double e = 1e-5;
    EXPECT_NEAR(hu, (hf.Height(u + e, v) - hf.Height(u - e, v)) / (2 * e), 1e-7);
    EXPECT_NEAR(hv, (hf.Height(u, v + e) - hf.Height(u, v - e)) / (2 * e), 1e-7);
    const double a = rng.Uniform(0, 2 * M_PI), du = std::cos(a), dv = std::sin(a), d = 1e-3;
    const double second = (hf.Height(u + d * du, v + d * dv) - 2 * h +
                           hf.Height(u - d * du, v - d * dv)) / (d * d);
    max_curv = std::max(max_curv, std::abs(second));
  }
  EXPECT_LE(max_slope, hf.slope_bound());
  EXPECT_LE(max_curv, hf.curvature_bound() * 1.001);
}

// g(t) = signed height of the ray point above the face's surface.
double Above(const Face& f, const Ray& r, double t) {
  const Eigen::Vector3d p = r.origin + t * r.dir;
  return p[f.axis] - f.offset - f.relief.Height(p[f.UAxis()], p[f.VAxis()]);
}

// Rays from above a rough floor at all incidences, including grazing ones:
// the hit lies on the surface and no crossing is skipped before it (dense
// sampling of g finds no sign change earlier).
TEST(Face, RoughIntersectionIsTheFirstCrossing) {
  Rng rng(11);
  Face f;
  f.axis = 2;
  f.offset = -1.0;
  f.bounds = {-1e4, 1e4, -1e4, 1e4};
  int grazing = 0, hits = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    f.relief = HeightField::Random(rng, 4, 0.1, 0.3, 2.0);  // steep: slopes up to ~0.9
    Ray r;
    r.origin = Eigen::Vector3d(rng.Uniform(-10, 10), rng.Uniform(-10, 10), rng.Uniform(-0.9, 3.0));
    // Elevation down to -0.2 deg: many rays are near-grazing.
    const double el = -std::pow(10.0, rng.Uniform(-2.5, 0.0)) * M_PI / 2;
    const double az = rng.Uniform(0, 2 * M_PI);
    r.dir = Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    if (std::abs(r.dir.z()) < f.relief.slope_bound()) ++grazing;
    double t = 0;
    const bool hit = f.Intersect(r, 0.0, 500.0, &t);
    // Reference: march g at 1 mm steps from 0 to the hit (or 500 m) where
    // the ray is inside the slab that holds the surface.
    const double end = hit ? t : 500.0;
    const double g0 = Above(f, r, 0.0);
    ASSERT_GT(g0, 0.0);
    const double amp = f.relief.amplitude_bound();
    const double slab_in = (r.origin.z() - (f.offset + amp)) / -r.dir.z();
    double first = kInf;
    for (double s = std::max(0.001, slab_in); s < end - 0.002; s += 0.001)
      if (Above(f, r, s) <= 0.0) {
        first = s;
        break;
      }
    EXPECT_EQ(first, kInf) << "crossing at " << first << " before reported hit " << end;
    if (hit) {
      ++hits;
      EXPECT_LT(std::abs(Above(f, r, t)), 1e-7);
      EXPECT_LT(f.Distance(r.origin + t * r.dir), 1e-7);
    } else {
      // No hit within 500 m: the ray ends above the surface.
      EXPECT_GT(Above(f, r, 500.0), 0.0);
    }
  }
  EXPECT_GT(grazing, 400);
  EXPECT_GT(hits, 1500);
}

// A flat face with a steep bump (a 30 cm bulge over 1 m): rays at every
// incidence hit the bumped surface, and no crossing comes before the hit.
TEST(Face, BumpedSurfaceIntersectionIsTheFirstCrossing) {
  Rng rng(17);
  Face f;
  f.axis = 2;
  f.offset = -1.0;
  f.bounds = {-1e4, 1e4, -1e4, 1e4};
  f.relief.AddBump({0.3, 0.0, 1.0, 0.0, 1.0});
  int hits = 0, on_bump = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    Ray r;
    r.origin = Eigen::Vector3d(rng.Uniform(-3, 3), rng.Uniform(-3, 3), rng.Uniform(-0.6, 1.0));
    const double el = -std::pow(10.0, rng.Uniform(-2.0, 0.0)) * M_PI / 2;
    // Aim near the bump so that many rays meet its flanks.
    const double az = std::atan2(-r.origin.y(), -r.origin.x()) + rng.Uniform(-0.3, 0.3);
    r.dir = Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    double t = 0;
    const bool hit = f.Intersect(r, 0.0, 200.0, &t);
    ASSERT_GT(Above(f, r, 0.0), 0.0);
    const double end = hit ? t : 200.0;
    for (double s = 0.001; s < end - 0.002; s += 0.001)
      ASSERT_GT(Above(f, r, s), 0.0) << "crossing at " << s << " before reported hit " << end;
    if (!hit) continue;
    ++hits;
    EXPECT_LT(std::abs(Above(f, r, t)), 1e-7);
    const Eigen::Vector3d p = r.origin + t * r.dir;
    on_bump += std::abs(p.x()) < 0.5 && std::abs(p.y()) < 0.5;
  }
  EXPECT_GT(hits, 900);
  EXPECT_GT(on_bump, 50);
}

TEST(Face, BoundsAndHolesLetRaysThrough) {
  Face wall;
  wall.axis = 1;  // y = 2, u = z, v = x
  wall.offset = 2.0;
  wall.bounds = {0.0, 3.0, -5.0, 5.0};
  wall.holes.push_back({0.0, 2.0, 1.0, 2.0});  // a doorway: z in [0, 2], x in [1, 2]
  Ray r;
  r.dir = Eigen::Vector3d::UnitY();
  double t = 0;
  r.origin = Eigen::Vector3d(0.0, 0.0, 1.0);
  ASSERT_TRUE(wall.Intersect(r, 0, 100, &t));
  EXPECT_NEAR(t, 2.0, 1e-12);
  r.origin = Eigen::Vector3d(1.5, 0.0, 1.0);  // through the doorway
  EXPECT_FALSE(wall.Intersect(r, 0, 100, &t));
  r.origin = Eigen::Vector3d(1.5, 0.0, 2.5);  // above it
  EXPECT_TRUE(wall.Intersect(r, 0, 100, &t));
  r.origin = Eigen::Vector3d(6.0, 0.0, 1.0);  // beyond the wall's end
  EXPECT_FALSE(wall.Intersect(r, 0, 100, &t));
  r.origin = Eigen::Vector3d(0.0, 0.0, 1.0);
  EXPECT_FALSE(wall.Intersect(r, 0, 1.5, &t));  // t_max before the wall
}

// Inside test for the brute-force reference.
bool InsideBox(const Box& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = b.R_world_box.transpose() * (p - b.center);
  return (q.cwiseAbs() - b.half).maxCoeff() <= 0.0;
}
bool InsideCylinder(const Cylinder& c, const Eigen::Vector3d& p) {
  const Eigen::Vector3d w = p - c.center;
  const double a = w.dot(c.axis);
  return std::abs(a) <= c.half_length && (w - a * c.axis).norm() <= c.radius;
}

template <typename Shape, typename Inside>
void CheckAgainstMarching(const Shape& shape, Inside inside, Rng& rng, int* hits) {
  for (int i = 0; i < 200; ++i) {
    Ray r;
    r.origin = shape.center + RandomUnit(rng) * rng.Uniform(3.0, 8.0);
    // Aim near the shape so that about half of the rays hit.
    const Eigen::Vector3d target = shape.center + RandomUnit(rng) * rng.Uniform(0.0, 2.0);
    r.dir = (target - r.origin).normalized();
    if (inside(r.origin)) continue;
    double t = 0;
    const bool hit = shape.Intersect(r, 0.0, 50.0, &t);
    // March to the first sample inside, then bisect the step that entered
    // down to 1e-7 m (the shapes are convex: a ray is inside along one
    // interval). 2 mm steps, and 0.5 mm where they found nothing but the
    // ray grazes the shape.
    const auto march = [&](double step) {
      for (double s = step; s < 20.0; s += step)
        if (inside(r.origin + s * r.dir)) {
          double outside_s = s - step, inside_s = s;
          while (inside_s - outside_s > 1e-7) {
            const double mid = 0.5 * (outside_s + inside_s);
            (inside(r.origin + mid * r.dir) ? inside_s : outside_s) = mid;
          }
          return inside_s;
        }
      return kInf;
    };
    double first = march(0.002);
    if (first == kInf && hit) first = march(0.0005);
    if (!hit) {
      EXPECT_EQ(first, kInf);
      continue;
    }
    ++*hits;
    EXPECT_NEAR(t, first, 1e-6);
    EXPECT_LT(shape.Distance(r.origin + t * r.dir), 1e-9);
  }
}

TEST(Box, IntersectionMatchesMarchingForOrientedBoxes) {
  Rng rng(5);
  int hits = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Box b;
    b.center = Eigen::Vector3d(rng.Uniform(-3, 3), rng.Uniform(-3, 3), rng.Uniform(-3, 3));
    b.R_world_box = Eigen::AngleAxisd(rng.Uniform(0, M_PI), RandomUnit(rng)).toRotationMatrix();
    b.half = Eigen::Vector3d(rng.Uniform(0.1, 1.5), rng.Uniform(0.1, 1.5), rng.Uniform(0.1, 1.5));
    CheckAgainstMarching(
        b, [&](const Eigen::Vector3d& p) { return InsideBox(b, p); }, rng, &hits);
    // The axis-aligned bounds contain sampled surface points.
    const Eigen::AlignedBox3d bounds = b.Bounds();
    for (int k = 0; k < 20; ++k) {
      Eigen::Vector3d q(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
      EXPECT_TRUE(bounds.contains(b.center + b.R_world_box * q.cwiseProduct(b.half)));
    }
  }
  EXPECT_GT(hits, 1000);
}

TEST(Cylinder, IntersectionMatchesMarchingIncludingCaps) {
  Rng rng(6);
  int hits = 0;
  for (int trial = 0; trial < 20; ++trial) {
    Cylinder c;
    c.center = Eigen::Vector3d(rng.Uniform(-3, 3), rng.Uniform(-3, 3), rng.Uniform(-3, 3));
    c.axis = RandomUnit(rng);
    c.radius = rng.Uniform(0.1, 1.0);
    c.half_length = rng.Uniform(0.2, 2.0);
    CheckAgainstMarching(
        c, [&](const Eigen::Vector3d& p) { return InsideCylinder(c, p); }, rng, &hits);
    const Eigen::AlignedBox3d bounds = c.Bounds();
    const Eigen::Vector3d n = c.axis.unitOrthogonal(), m = c.axis.cross(n);
    for (int k = 0; k < 20; ++k) {
      const double ang = rng.Uniform(0, 2 * M_PI);
      const Eigen::Vector3d q = c.center + rng.Uniform(-1, 1) * c.half_length * c.axis +
                                c.radius * (std::cos(ang) * n + std::sin(ang) * m);
      EXPECT_TRUE(bounds.contains(q));
    }
  }
  EXPECT_GT(hits, 1000);
}

// The bucketed ray caster returns the same first hit as testing every face
// and feature, for rays from anywhere inside the tunnel and the hall.
TEST(World, BucketedRaycastEqualsBruteForce) {
  for (const char* preset : {"tunnel", "hall", "corridor"}) {
    auto sim = Simulator::Create(*PresetOptions(preset));
    ASSERT_TRUE(sim.ok());
    const World& w = (*sim)->world();
    const WorldLayout& L = (*sim)->layout();
    Rng rng(17);
    int hits = 0;
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector3d o(
          rng.Uniform(L.x_entrance + 0.5, std::min(L.x_end, L.clutter_end + 60.0)),
          rng.Uniform(L.y_center - L.half_width + 0.5, L.y_center + L.half_width - 0.5),
          rng.Uniform(L.z_floor + 0.5, L.z_ceiling - 0.5));
      const Eigen::Vector3d d = RandomUnit(rng);
      double best = 120.0;
      for (const Face& f : w.faces()) {
        double t;
        if (f.Intersect({o, d}, 1e-9, best, &t)) best = t;
      }
      bool inside_feature = false;
      for (const Box& b : w.boxes()) {
        inside_feature |= InsideBox(b, o);
        double t;
        if (b.Intersect({o, d}, 0.0, best, &t)) best = t;
      }
      for (const Cylinder& c : w.cylinders()) {
        inside_feature |= InsideCylinder(c, o);
        double t;
        if (c.Intersect({o, d}, 0.0, best, &t)) best = t;
      }
      if (inside_feature) continue;
      RayHit hit;
      const bool found = w.Raycast(o, d, 120.0, &hit);
      if (best < 120.0) {
        ASSERT_TRUE(found) << preset;
        EXPECT_NEAR(hit.range, best, 1e-6) << preset;  // root tolerance, order-dependent
        EXPECT_LT(w.DistanceToSurface(o + hit.range * d), 1e-7);
        ++hits;
      } else {
        EXPECT_FALSE(found) << preset;
      }
    }
    EXPECT_GT(hits, 15000) << preset;
  }
}

}  // namespace
}  // namespace rvlio::sim
