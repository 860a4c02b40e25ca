// The shipped configuration files: config/default.yaml cannot drift from the
// built-in defaults, the paper presets hold the paper's values, and every
// file under config/ loads and validates.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "config_test_util.h"
#include "rvlio/config/config.h"
#include "rvlio/config/config_json.h"

namespace rvlio {
namespace {

const std::string kConfigDir = std::string(RVLIO_SOURCE_DIR) + "/config";

TEST(ConfigFiles, DefaultYamlListsEveryKnownKey) {
  const std::string path = kConfigDir + "/default.yaml";
  Configuration options;
  ConfigSources sources;
  ASSERT_TRUE(ApplyYamlFile(options, path, &sources).ok());
  const std::vector<std::string> keys = ListKeys(options);
  ASSERT_GT(keys.size(), 40u);
  for (const auto& key : keys) {
    auto it = sources.find(key);
    ASSERT_NE(it, sources.end()) << key << " is missing from config/default.yaml";
    EXPECT_EQ(it->second.rfind(path + ":", 0), 0u) << key << " -> " << it->second;
  }
  EXPECT_EQ(sources.size(), keys.size());  // unknown keys are rejected anyway
}

TEST(ConfigFiles, DefaultYamlValuesEqualTheBuiltInDefaults) {
  StatusOr<Configuration> loaded = LoadConfig({kConfigDir + "/default.yaml"}, {});
  ASSERT_TRUE(loaded.ok()) << loaded.status().message();
  const Configuration builtin;
  const nlohmann::json a = ToJson(*loaded), b = ToJson(builtin);
  for (const auto& key : ListKeys(builtin)) {
    std::string p = "/" + key;
    std::replace(p.begin(), p.end(), '.', '/');
    EXPECT_EQ(a.at(nlohmann::json::json_pointer(p)), b.at(nlohmann::json::json_pointer(p)))
        << key << " in config/default.yaml differs from the built-in default";
  }
  EXPECT_EQ(a, b);
  // And the built-in defaults themselves pass validation.
  Configuration copy = builtin;
  EXPECT_TRUE(copy.Validate().ok()) << copy.Validate().message();
}

TEST(ConfigFiles, PaperSimPresetHoldsThePaperValues) {
  StatusOr<Configuration> r = LoadConfig({kConfigDir + "/paper_sim.yaml"}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.eps0, 0.510303);
  EXPECT_EQ(r->rv.eps1, 0.11303);
  EXPECT_EQ(r->rv.k0, 695.07);
  EXPECT_TRUE(r->rv.enabled && r->rv.reinforce && r->rv.repair);
}

TEST(ConfigFiles, PaperRealPresetHoldsThePaperValues) {
  StatusOr<Configuration> r = LoadConfig({kConfigDir + "/paper_real.yaml"}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->rv.eps0, 0.290713);
  EXPECT_EQ(r->rv.eps1, 0.29071);
  EXPECT_EQ(r->rv.k0, 0.053);
  EXPECT_TRUE(r->rv.enabled && r->rv.reinforce && r->rv.repair);
}

TEST(ConfigFiles, PresetsOverrideOnlyTheRvSection) {
  // A preset after a sensor file keeps the sensor's keys.
  StatusOr<Configuration> r =
      LoadConfig({kConfigDir + "/sensors/os0_32.yaml", kConfigDir + "/paper_real.yaml"}, {});
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_EQ(r->lidar.type, "ouster");
  EXPECT_EQ(r->rv.eps0, 0.290713);
  nlohmann::json diff = nlohmann::json::diff(ToJson(Configuration{}), ToJson(*r));
  for (const auto& op : diff) {
    const std::string path = op["path"];
    EXPECT_TRUE(path.rfind("/rv/", 0) == 0 || path.rfind("/lidar/", 0) == 0 ||
                path.rfind("/imu/", 0) == 0 || path.rfind("/extrinsics/", 0) == 0)
        << path;
  }
}

TEST(ConfigFiles, EveryShippedFileLoadsAndValidates) {
  std::vector<std::string> files;
  for (const char* sub : {"", "/sensors"})
    for (const auto& e : std::filesystem::directory_iterator(kConfigDir + sub))
      if (e.path().extension() == ".yaml") files.push_back(e.path().string());
  ASSERT_GE(files.size(), 5u);  // default, two presets, at least two sensors
  for (const auto& f : files) {
    StatusOr<Configuration> r = LoadConfig({f}, {});
    EXPECT_TRUE(r.ok()) << f << ": " << r.status().message();
  }
}

TEST(ConfigFiles, SensorExamplesDescribeOusterSensors) {
  for (const char* name : {"os1_32.yaml", "os0_32.yaml"}) {
    StatusOr<Configuration> r = LoadConfig({kConfigDir + "/sensors/" + name}, {});
    ASSERT_TRUE(r.ok()) << name << ": " << r.status().message();
    EXPECT_EQ(r->lidar.type, "ouster") << name;
    EXPECT_EQ(r->lidar.topic, "/os_cloud_node/points") << name;
    EXPECT_EQ(r->imu.topic, "/os_cloud_node/imu") << name;
    const auto& q = r->extrinsics.imu_T_lidar.rotation_xyzw;
    EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-12) << name;
  }
}

}  // namespace
}  // namespace rvlio
