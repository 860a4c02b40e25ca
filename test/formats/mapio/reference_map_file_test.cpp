// The inputs of `run --map` (formats/reference_map_file.h) in a national grid:
// the map and the initial pose enter the map's local frame together, and a
// map a search structure cannot hold whole is refused, naming the file.
#include "rvlio/formats/reference_map_file.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/run_outputs.h"
#include "test_dir.h"

namespace rvlio {
namespace {

const Eigen::Vector3d kUtm(500000.0, 5400000.0, 0.0);

class ReferenceMapFileTest : public MapioTestDir {
 protected:
  // A floor and a wall (10 cm grid) around kUtm + (5, 0, 0), written as map.pcd (float64 x y z).
  std::string WriteMap(const std::string& name, std::vector<Eigen::Vector3d> extra = {}) const {
    std::vector<Eigen::Vector3d> p;
    for (int i = 0; i < 100; ++i)
      for (int j = 0; j < 40; ++j) {
        p.push_back(kUtm + Eigen::Vector3d(0.1 * i, -2.0 + 0.1 * j, 0.0));
        p.push_back(kUtm + Eigen::Vector3d(0.1 * i, 2.0, 0.1 * j));
      }
    p.insert(p.end(), extra.begin(), extra.end());
    EXPECT_TRUE(WriteMapPcd(Path(name), p).ok());
    return Path(name);
  }
};

TEST_F(ReferenceMapFileTest, MapAndInitialPoseEnterTheMapsLocalFrame) {
  const std::string map = WriteMap("utm.pcd");
  std::shared_ptr<const ReferenceMap> surface;
  std::vector<std::string> warnings;
  StatusOr<Localization> loc = LoadLocalization(map, "500003.25,5400000.5,1.5,0,0,90", "",
                                                OdometryOptions(), &surface, &warnings);
  ASSERT_TRUE(loc.ok()) << loc.status().message();
  EXPECT_TRUE(warnings.empty());  // float64 x y z
  EXPECT_EQ(loc->origin.t_user_local, kUtm);
  ASSERT_EQ(loc->initial_poses.size(), 1u);
  EXPECT_EQ(loc->initial_poses[0].p_world_imu, Eigen::Vector3d(3.25, 0.5, 1.5));
  ASSERT_NE(surface, nullptr);
  EXPECT_EQ(surface->Size(), 8000u);
  EXPECT_TRUE(surface->Bounds().contains(Eigen::Vector3d(5.0, 0.0, 0.0)));
  EXPECT_GT(loc->reference->Size(), 0u);
  NeighborBuffer nb;  // the local map answers at the local position of a surveyed point
  ASSERT_EQ(surface->KNearest(Eigen::Vector3d(2.0, 2.0, 1.0), 1, 0.05, &nb), 1);
  EXPECT_LT(std::sqrt(nb.dist2[0]), 1e-5);

  // The same pose from a TUM file in the map's frame.
  Trajectory tum(1);
  tum[0].t_ns = 1;
  tum[0].p_world_imu = kUtm + Eigen::Vector3d(3.25, 0.5, 1.5);
  ASSERT_TRUE(WriteTum(Path("start.tum"), tum).ok());
  loc = LoadLocalization(map, "", Path("start.tum"), OdometryOptions(), nullptr, nullptr);
  ASSERT_TRUE(loc.ok()) << loc.status().message();
  EXPECT_NEAR((loc->initial_poses[0].p_world_imu - Eigen::Vector3d(3.25, 0.5, 1.5)).norm(), 0.0,
              1e-9);
}

TEST_F(ReferenceMapFileTest, APointBeyondTheReachOrNotFiniteIsRefusedNamingTheMap) {
  const std::string stray = WriteMap("stray.pcd", {kUtm + Eigen::Vector3d(250000.0, 0.0, 0.0)});
  std::shared_ptr<const ReferenceMap> surface;  // 0.1 m voxels: 104.8 km of reach
  StatusOr<Localization> loc =
      LoadLocalization(stray, "500003,5400000,1.5,0,0,0", "", OdometryOptions(), &surface, nullptr);
  ASSERT_FALSE(loc.ok());
  EXPECT_EQ(loc.status().code(), StatusCode::kInvalidInput);
  EXPECT_EQ(loc.status().message().rfind("--map " + stray + ": 1 of 8001 points lie more than", 0),
            0u)
      << loc.status().message();
  // The association map alone (0.5 m voxels: 524 km of reach) holds it.
  EXPECT_TRUE(
      LoadLocalization(stray, "500003,5400000,1.5,0,0,0", "", OdometryOptions(), nullptr, nullptr)
          .ok());
  LocalOrigin origin;  // refine --map and merge --map read it the same way
  EXPECT_FALSE(LoadReferenceMap(stray, LocalizationOptions(), &surface, &origin, nullptr).ok());
  const StatusOr<std::shared_ptr<const ReferenceMap>> alone =
      LoadReferenceSurface(stray, &origin, nullptr);
  ASSERT_FALSE(alone.ok());
  EXPECT_NE(alone.status().message().find("104.8 km"), std::string::npos);

  const std::string nan =
      WriteMap("nan.pcd", {Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0)});
  loc = LoadLocalization(nan, "500003,5400000,1.5,0,0,0", "", OdometryOptions(), nullptr, nullptr);
  ASSERT_FALSE(loc.ok());
  EXPECT_NE(loc.status().message().find("nan.pcd"), std::string::npos);
  EXPECT_NE(loc.status().message().find("non-finite"), std::string::npos);

  // An initial pose in another frame (local coordinates given with a UTM map).
  loc = LoadLocalization(WriteMap("ok.pcd"), "3,0,1.5,0,0,0", "", OdometryOptions(), nullptr,
                         nullptr);
  ASSERT_FALSE(loc.ok());
  EXPECT_NE(loc.status().message().find("initial position (3.000, 0.000, 1.500)"),
            std::string::npos)
      << loc.status().message();
}

// A UTM map stored as float32 (PCL's PointXYZ) holds only what float32 holds
// there: it is used, with one warning naming the file and the step.
TEST_F(ReferenceMapFileTest, AFloat32MapFarFromZeroIsUsedWithAWarning) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 40; ++j)
      cloud.push_back(pcl::PointXYZ(static_cast<float>(kUtm.x() + 0.1 * i),
                                    static_cast<float>(kUtm.y() - 2.0 + 0.1 * j), 0.0f));
  ASSERT_EQ(pcl::PCDWriter().writeBinary(Path("f4.pcd"), cloud), 0);
  std::vector<std::string> warnings;
  LocalOrigin origin;
  std::shared_ptr<const ReferenceMap> surface;
  ASSERT_TRUE(LoadReferenceMap(Path("f4.pcd"), LocalizationOptions(), &surface, &origin, &warnings)
                  .ok());
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind("--map " + Path("f4.pcd") + ": x y z are float32", 0), 0u)
      << warnings[0];
  EXPECT_NE(warnings[0].find("steps by 0.5 m"), std::string::npos) << warnings[0];
  // Near zero float32 is what map.pcd itself is: no warning.
  pcl::PointCloud<pcl::PointXYZ> near;
  near.push_back(pcl::PointXYZ(8191.0f, 0.0f, 0.0f));
  ASSERT_EQ(pcl::PCDWriter().writeBinary(Path("near.pcd"), near), 0);
  warnings.clear();
  ASSERT_TRUE(LoadReferenceSurface(Path("near.pcd"), &origin, &warnings).ok());
  EXPECT_TRUE(warnings.empty());
}

}  // namespace
}  // namespace rvlio
