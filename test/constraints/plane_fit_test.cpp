#include "rvlio/constraints/plane_fit.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace rvlio {
namespace {

const PlaneThresholds kDefault = PlaneThresholds::From(ConstraintOptions());

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  // Normals are unsigned: angle between the lines.
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / M_PI;
}

Eigen::Vector3d RandomUnit(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Vector3d(n(*rng), n(*rng), n(*rng)).normalized();
}

// Orthonormal in-plane axes of a plane with normal u.
void PlaneAxes(const Eigen::Vector3d& u, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  *e1 = u.unitOrthogonal();
  *e2 = u.cross(*e1);
}

TEST(PlaneFit, NoisyPlaneRecoversNormal) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.002);  // 2 mm
  double worst_deg = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d u = RandomUnit(&rng);
    const Eigen::Vector3d origin = 50.0 * RandomUnit(&rng) * unit(rng);
    Eigen::Vector3d e1, e2;
    PlaneAxes(u, &e1, &e2);
    const int n = 5 + trial % 16;
    const double radius = 0.3 + 0.7 * unit(rng);
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * unit(rng), r = radius * std::sqrt(unit(rng));
      pts.push_back(origin + r * std::cos(a) * e1 + r * std::sin(a) * e2 + noise(rng) * u);
    }
    const LocalPlane plane = FitLocalPlane(pts, kDefault);
    if (plane.status == PlaneStatus::kLineLike) continue;  // rare unlucky draws of 5 points
    ASSERT_TRUE(plane.valid()) << ToString(plane.status) << " trial " << trial;
    EXPECT_NEAR(plane.normal.norm(), 1.0, 1e-12);
    EXPECT_LT(std::abs(u.dot(plane.centroid - origin)), 0.01);
    EXPECT_LE(plane.eigenvalues(0), plane.eigenvalues(1));
    EXPECT_LE(plane.eigenvalues(1), plane.eigenvalues(2));
    EXPECT_LT(plane.max_distance, 0.02);
    worst_deg = std::max(worst_deg, AngleDeg(plane.normal, u));
  }
  EXPECT_LT(worst_deg, 3.0);
}

TEST(PlaneFit, ExactOnNoiseFreePlanesFarFromTheOrigin) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d u = RandomUnit(&rng);
    const Eigen::Vector3d origin = Eigen::Vector3d(1000.0, -2000.0, 300.0) + RandomUnit(&rng);
    Eigen::Vector3d e1, e2;
    PlaneAxes(u, &e1, &e2);
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 5; ++i) pts.push_back(origin + unit(rng) * e1 + unit(rng) * e2);
    const LocalPlane plane = FitLocalPlane(pts, PlaneThresholds{0.0, 0.1, 0.1});
    ASSERT_TRUE(plane.valid()) << ToString(plane.status);
    EXPECT_LT(AngleDeg(plane.normal, u), 1e-5);
    EXPECT_LT(plane.max_distance, 1e-9);
    // The paper's form a x + b y + c z + 1 = 0 holds on every point.
    const Eigen::Vector3d abc = plane.PaperCoefficients();
    for (const auto& p : pts) EXPECT_NEAR(abc.dot(p) + 1.0, 0.0, 1e-9);
  }
}

// Five consecutive returns of one beam on a wall (a conic arc, locally a
// line), as a 32-beam LiDAR leaves them: any plane through them fits.
TEST(PlaneFit, RingLineIsRejected) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int trial = 0; trial < 500; ++trial) {
    const double wall = 3.0 + 7.0 * unit(rng);  // y = wall
    const double elevation = (-22.5 + 45.0 * unit(rng)) * M_PI / 180.0;
    const double azimuth0 = (30.0 + 120.0 * unit(rng)) * M_PI / 180.0;  // facing the wall
    const double step = (0.35 + 1.0 * unit(rng)) * M_PI / 180.0;
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 5; ++i) {
      const double az = azimuth0 + i * step;
      const Eigen::Vector3d ray(std::cos(elevation) * std::cos(az),
                                std::cos(elevation) * std::sin(az), std::sin(elevation));
      pts.push_back((wall / ray.y() + noise(rng)) * ray);
    }
    const LocalPlane plane = FitLocalPlane(pts, kDefault);
    EXPECT_EQ(plane.status, PlaneStatus::kLineLike) << "trial " << trial;
  }
}

// Points on both walls right at the edge where they meet: a line again.
TEST(PlaneFit, EdgeBetweenTwoWallsIsRejected) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d edge_dir = RandomUnit(&rng);
    Eigen::Vector3d n1, n2;  // the two wall normals, perpendicular to the edge
    PlaneAxes(edge_dir, &n1, &n2);
    const Eigen::Vector3d a = n1, b = std::cos(1.2) * n1 + std::sin(1.2) * n2;  // wall directions
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 6; ++i) {
      const Eigen::Vector3d away = (i % 2 == 0 ? a : b) * 0.02 * unit(rng);  // <= 2 cm off the edge
      pts.push_back(Eigen::Vector3d(5, 1, 2) + (0.1 * i + 0.02 * unit(rng)) * edge_dir + away);
    }
    EXPECT_EQ(FitLocalPlane(pts, kDefault).status, PlaneStatus::kLineLike) << "trial " << trial;
  }
}

// A neighbourhood straddling the corner of two perpendicular walls.
TEST(PlaneFit, CornerIsRejected) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const double along = 0.05 + 0.15 * i + jitter(rng), up = 0.15 * j + jitter(rng);
        pts.emplace_back(along, 0.0, up);  // wall y = 0
        pts.emplace_back(0.0, along, up);  // wall x = 0
      }
    }
    const PlaneStatus status = FitLocalPlane(pts, kDefault).status;
    EXPECT_TRUE(status == PlaneStatus::kNotFlat || status == PlaneStatus::kFarFromPlane)
        << ToString(status) << " trial " << trial;
  }
}

TEST(PlaneFit, PointFarFromPlaneIsRejected) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 10; ++i) {
    const double a = 2 * M_PI * i / 10;
    pts.emplace_back(std::cos(a), std::sin(a), 0.0);
  }
  pts.emplace_back(0.0, 0.0, 0.25);
  const LocalPlane plane = FitLocalPlane(pts, kDefault);
  EXPECT_EQ(plane.status, PlaneStatus::kFarFromPlane);
  EXPECT_GT(plane.max_distance, 0.2);
  EXPECT_LT(AngleDeg(plane.normal, Eigen::Vector3d::UnitZ()), 1e-6);
  // Raising the threshold accepts the same neighbourhood.
  EXPECT_TRUE(FitLocalPlane(pts, PlaneThresholds{0.1, 0.1, 0.3}).valid());
}

// normal_std predicts the spread of the fitted normal: Monte Carlo over the
// noise of a fixed 5-point layout (a 2 + 3 split over two ring lines).
TEST(PlaneFit, NormalStdPredictsTheNormalSpread) {
  std::mt19937 rng(6);
  const double sigma = 0.01;
  std::normal_distribution<double> noise(0.0, sigma);
  const std::vector<Eigen::Vector3d> layout = {
      Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.1, 0.0, 0.0),
      Eigen::Vector3d(0.2, 0.0, 0.0), Eigen::Vector3d(0.05, 0.15, 0.0),
      Eigen::Vector3d(0.15, 0.15, 0.0)};
  PlaneThresholds t{0.0, 1.0, 1.0, 0.0, sigma};
  double sum_tilt2 = 0.0, sum_predicted = 0.0;
  const int trials = 4000;
  for (int i = 0; i < trials; ++i) {
    std::vector<Eigen::Vector3d> pts = layout;
    for (auto& p : pts) p.z() += noise(rng);
    const LocalPlane plane = FitLocalPlane(pts, t);
    ASSERT_TRUE(plane.valid()) << ToString(plane.status);
    const double tilt = std::acos(std::min(1.0, std::abs(plane.normal.z())));
    sum_tilt2 += tilt * tilt;
    sum_predicted += plane.normal_std;
  }
  // Total tilt (two axes) vs the worst-axis prediction: within a factor 2.
  const double empirical = std::sqrt(sum_tilt2 / trials);
  const double predicted = sum_predicted / trials;
  EXPECT_GT(empirical, 0.5 * predicted);
  EXPECT_LT(empirical, 2.0 * predicted);
}

TEST(PlaneFit, UncertainNormalIsRejectedOnlyWhenAsked) {
  const std::vector<Eigen::Vector3d> small = {
      Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.1, 0.0, 0.003),
      Eigen::Vector3d(0.2, 0.0, -0.002), Eigen::Vector3d(0.05, 0.05, 0.004),
      Eigen::Vector3d(0.15, 0.05, -0.001)};
  std::vector<Eigen::Vector3d> wide = small;
  for (auto& p : wide) p.head<2>() *= 10.0;  // same noise, 10 times the extent
  const PlaneThresholds off{0.1, 0.1, 0.1, 0.0, 0.02};
  const PlaneThresholds on{0.1, 0.1, 0.1, 3.0 * M_PI / 180, 0.02};
  EXPECT_TRUE(FitLocalPlane(small, off).valid());
  const LocalPlane p_small = FitLocalPlane(small, on);
  EXPECT_EQ(p_small.status, PlaneStatus::kUncertain);
  EXPECT_GT(p_small.normal_std, 3.0 * M_PI / 180);
  const LocalPlane p_wide = FitLocalPlane(wide, on);
  EXPECT_TRUE(p_wide.valid()) << ToString(p_wide.status);
  EXPECT_NEAR(p_wide.normal_std / p_small.normal_std, 0.1, 0.005);  // ~ 1 / extent
}

// The fit's eigen-decomposition agrees with Eigen's iterative solver on
// neighbourhoods of every shape: planar, line-like, blobs, near-degenerate.
TEST(PlaneFit, EigenvaluesAndNormalMatchAReferenceSolver) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 3000; ++trial) {
    // Random anisotropic Gaussian cloud: axis scales spanning 6 decades.
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const Eigen::Vector3d scale(std::pow(10.0, -4.0 + 3.0 * unit(rng)),
                                std::pow(10.0, -3.0 + 3.0 * unit(rng)),
                                std::pow(10.0, -1.0 + 1.0 * unit(rng)));
    const int n = 3 + trial % 18;
    std::vector<Eigen::Vector3d> pts;
    const Eigen::Vector3d origin = 100.0 * Eigen::Vector3d(g(rng), g(rng), g(rng));
    for (int i = 0; i < n; ++i)
      pts.push_back(origin + R * scale.cwiseProduct(Eigen::Vector3d(g(rng), g(rng), g(rng))));
    const LocalPlane plane = FitLocalPlane(pts, PlaneThresholds{0.0, 1.0, 1e9, 0.0, 0.0});

    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : pts) c += p;
    c /= n;
    Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
    for (const auto& p : pts) C += (p - c) * (p - c).transpose();
    C /= n;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ref(C);
    const Eigen::Vector3d lambda = ref.eigenvalues();
    const double tol = 1e-9 * lambda(2);
    EXPECT_NEAR(plane.eigenvalues(2), lambda(2), tol) << "trial " << trial;
    EXPECT_NEAR(plane.eigenvalues(1), lambda(1), tol + 1e-6 * lambda(1)) << "trial " << trial;
    EXPECT_NEAR(plane.eigenvalues(0), std::max(0.0, lambda(0)), tol) << "trial " << trial;
    // The normal is defined when lambda_min is separated from lambda_mid.
    if (lambda(0) < 0.5 * lambda(1) && lambda(1) > 1e-6 * lambda(2)) {
      EXPECT_LT(AngleDeg(plane.normal, ref.eigenvectors().col(0)), 1e-3) << "trial " << trial;
    }
    EXPECT_NEAR(plane.normal.norm(), 1.0, 1e-12);
  }
}

TEST(PlaneFit, TooFewAndDegenerate) {
  std::vector<Eigen::Vector3d> pts = {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 4)};
  EXPECT_EQ(FitLocalPlane(pts, kDefault).status, PlaneStatus::kTooFewPoints);
  pts = {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 3)};
  EXPECT_EQ(FitLocalPlane(pts, kDefault).status, PlaneStatus::kDegenerate);
  pts = {Eigen::Vector3d(NAN, 2, 3), Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 5, 3)};
  EXPECT_EQ(FitLocalPlane(pts, kDefault).status, PlaneStatus::kDegenerate);
}

}  // namespace
}  // namespace rvlio
