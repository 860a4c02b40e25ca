// The measurement model on real scans: small_gicp's outdoor scan pair
// (test/data/small_gicp_pair), aligned with rvlio's point-to-plane
// association (the working map's k-NN, plane fit and validity tests,
// constraints/plane_association.h) and a plain Gauss-Newton solve of those
// constraints (no IMU, no RV), agrees with the transform small_gicp's own
// registration finds. A deliberately wrong plane model (every plane moved
// 10 cm along its normal) must fail the same tolerance, so the test can fail.
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/constraints/robust_kernel.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

std::string PairCapture(const std::string& name) {
  return std::string(RVLIO_TEST_DATA) + "/small_gicp_pair/" + name;
}

// x y z of a binary little-endian PLY whose vertex properties are all float32
// (CloudCompare's output: x y z scalar_intensity).
std::vector<Eigen::Vector3d> ReadPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  int64_t vertices = 0;
  int floats = 0;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream s(line);
    std::string word, type;
    s >> word;
    if (word == "element") s >> type >> vertices;
    if (word == "property") {
      s >> type;
      EXPECT_EQ(type, "float") << line;
      ++floats;
    }
  }
  std::vector<float> data(static_cast<size_t>(vertices * floats));
  in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size() * sizeof(float)));
  EXPECT_EQ(in.gcount(), static_cast<std::streamsize>(data.size() * sizeof(float)));
  std::vector<Eigen::Vector3d> points;
  for (int64_t i = 0; i < vertices; ++i)
    points.emplace_back(data[i * floats], data[i * floats + 1], data[i * floats + 2]);
  return points;
}

Pose3 ReadTransform(const std::string& path) {
  std::ifstream in(path);
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) in >> T(r, c);
  return Pose3(Eigen::Matrix3d(T.topLeftCorner<3, 3>()), Eigen::Vector3d(T.topRightCorner<3, 1>()));
}

// The source points downsampled by the project's scan preprocessor (0.25 m voxels).
std::vector<Eigen::Vector3d> Downsampled(const std::vector<Eigen::Vector3d>& points) {
  LidarOptions lidar;
  lidar.voxel_size = 0.25;
  lidar.min_range = 0.5;
  lidar.max_range = 100.0;
  Scan scan, out;
  for (const Eigen::Vector3d& p : points) {
    LidarPoint lp;
    lp.p_lidar = p.cast<float>();
    scan.points.push_back(lp);
  }
  ScanPreprocessor(lidar).Downsample(scan, &out);
  std::vector<Eigen::Vector3d> kept;
  for (const LidarPoint& p : out.points) kept.push_back(p.p_lidar.cast<double>());
  return kept;
}

struct Alignment {
  Pose3 T_target_source;
  int constraints = 0;
};

// Gauss-Newton on [dtheta, dp] (right perturbation of the rotation) with
// re-association every iteration and the project's Huber weights;
// `plane_offset_m` moves every associated plane along its normal (0: the
// project's plane model).
Alignment Align(const std::vector<Eigen::Vector3d>& source, const VoxelMap& target,
                double plane_offset_m) {
  ConstraintOptions options;
  Pose3 T;  // identity start: the pair is 0.5 m and 0.7 deg apart
  Alignment out;
  for (int iter = 0; iter < 30; ++iter) {
    ConstraintList constraints;
    AssociationStats stats;
    Associate(source, T, Pose3(), target, options, &constraints, &stats);
    for (Constraint& c : constraints) c.q_world += plane_offset_m * c.normal_world;
    ApplyHuberWeights(0.1, &constraints);
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    for (const Constraint& c : constraints) {
      Eigen::Matrix<double, 1, 6> J;
      const double r = PointToPlaneResidual(c, T, Pose3(), &J);
      H += c.weight * J.transpose() * J;
      b += c.weight * J.transpose() * r;
    }
    const Eigen::Matrix<double, 6, 1> dx = H.ldlt().solve(-b);
    T = Pose3(T.R * so3::Exp(dx.head<3>()), T.t + dx.tail<3>());
    out.constraints = static_cast<int>(constraints.size());
    if (dx.norm() < 1e-7) break;
  }
  out.T_target_source = T;
  return out;
}

class RealScanPairTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    source_ = new std::vector<Eigen::Vector3d>(Downsampled(ReadPly(PairCapture("source.ply"))));
    MapOptions map_options;
    map_options.voxel_size = 0.5;
    target_ = new VoxelMap(map_options);
    target_->Insert(ReadPly(PairCapture("target.ply")));
  }
  static void TearDownTestSuite() {
    delete source_;
    delete target_;
  }
  static std::vector<Eigen::Vector3d>* source_;
  static VoxelMap* target_;
};
std::vector<Eigen::Vector3d>* RealScanPairTest::source_ = nullptr;
VoxelMap* RealScanPairTest::target_ = nullptr;

TEST_F(RealScanPairTest, PointToPlaneAgreesWithSmallGicp) {
  ASSERT_GT(source_->size(), 5000u);
  const Pose3 peer = ReadTransform(PairCapture("T_target_source.txt"));
  const Alignment a = Align(*source_, *target_, 0.0);
  EXPECT_GT(a.constraints, 3000);
  const double dt_m = (a.T_target_source.t - peer.t).norm();
  const double dr_deg = so3::Log(peer.R.transpose() * a.T_target_source.R).norm() * 180.0 / M_PI;
  EXPECT_LT(dt_m, 0.02) << a.T_target_source.t.transpose() << " vs " << peer.t.transpose();
  EXPECT_LT(dr_deg, 0.1);
  std::printf("small_gicp pair: translation %.4f m and rotation %.4f deg from small_gicp's, %d constraints\n",
              dt_m, dr_deg, a.constraints);
}

TEST_F(RealScanPairTest, AWrongPlaneModelFails) {
  const Pose3 peer = ReadTransform(PairCapture("T_target_source.txt"));
  const Alignment a = Align(*source_, *target_, 0.10);
  const double dt_m = (a.T_target_source.t - peer.t).norm();
  const double dr_deg = so3::Log(peer.R.transpose() * a.T_target_source.R).norm() * 180.0 / M_PI;
  EXPECT_TRUE(dt_m > 0.02 || dr_deg > 0.1) << dt_m << " m, " << dr_deg << " deg";
  std::printf("planes moved 10 cm along their normals: %.4f m, %.4f deg from small_gicp's\n", dt_m, dr_deg);
}

}  // namespace
}  // namespace rvlio
