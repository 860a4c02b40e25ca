// End to end: `rvlio eval --map` on constructed clouds (a plane and its copy
// 2 cm off) and on bad input (one error line naming the file, exit 2).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_util.h"

namespace rvlio::testing_cli {
namespace {

// Binary x y z float32 PCD.
void WritePcd(const std::string& path, const std::vector<Eigen::Vector3f>& p) {
  std::ofstream out(path, std::ios::binary);
  out << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << p.size()
      << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << p.size() << "\nDATA binary\n";
  out.write(reinterpret_cast<const char*>(p.data()), static_cast<std::streamsize>(p.size() * 12));
}

// ASCII PLY.
void WritePly(const std::string& path, const std::vector<Eigen::Vector3f>& p) {
  std::ofstream out(path);
  out << "ply\nformat ascii 1.0\nelement vertex " << p.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const Eigen::Vector3f& x : p) out << x.x() << " " << x.y() << " " << x.z() << "\n";
}

std::vector<Eigen::Vector3f> Plane(int n, float z, float noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 3.0f);
  std::normal_distribution<float> e(0.0f, noise);
  std::vector<Eigen::Vector3f> p(n);
  for (Eigen::Vector3f& x : p) x = Eigen::Vector3f(u(rng), u(rng), z + e(rng));
  return p;
}

class EvalMapCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = MakeTempDir("rvlio_eval_map");
    ASSERT_FALSE(dir_.empty());
    WritePcd(dir_ + "/ref.pcd", Plane(60000, 0.0f, 0.0005f, 1));
    WritePly(dir_ + "/map.ply", Plane(10000, 0.02f, 0.001f, 2));
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  ToolRun Eval(const std::string& args) { return RunTool("eval " + args, dir_); }
  void ExpectBadInput(const std::string& args, const std::string& part) {
    ExpectOneErrorLine(Eval(args), "eval", part);
  }
  std::string dir_;
};

TEST_F(EvalMapCliTest, JsonGivesTheTwoCentimetreOffset) {
  const ToolRun r = Eval("--map " + dir_ + "/map.ply --ref-map " + dir_ + "/ref.pcd --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["accuracy"]["mean"].get<double>(), 0.02, 0.0005);
  EXPECT_NEAR(j["accuracy"]["median"].get<double>(), 0.02, 0.0005);
  EXPECT_GT(j["completeness"].get<double>(), 0.99);
  EXPECT_EQ(j["outlier_fraction"].get<double>(), 0.0);
  EXPECT_EQ(j["map_points"].get<int>(), 10000);
  EXPECT_EQ(j["ref_points"].get<int>(), 60000);
  EXPECT_GE(j["profile"].size(), 3u);
  EXPECT_TRUE(j["chamfer"].is_number());
  // The table: the same run, human-readable.
  const ToolRun table = Eval("--map " + dir_ + "/map.ply --ref-map " + dir_ + "/ref.pcd");
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("point-to-plane"), std::string::npos) << table.out;
  EXPECT_NE(table.out.find("completeness"), std::string::npos) << table.out;
}

TEST_F(EvalMapCliTest, BadInputIsOneLineExitTwo) {
  const std::string ref = " --ref-map " + dir_ + "/ref.pcd";
  std::ofstream(dir_ + "/empty.pcd").flush();
  WritePcd(dir_ + "/nopoints.pcd", {});
  std::vector<Eigen::Vector3f> nan = Plane(100, 0.0f, 0.0f, 3);
  nan[7].x() = std::numeric_limits<float>::quiet_NaN();
  WritePcd(dir_ + "/nan.pcd", nan);
  std::vector<Eigen::Vector3f> far = Plane(100, 0.0f, 0.0f, 4);
  for (Eigen::Vector3f& p : far) p *= 1000.0f;  // millimetres
  WritePcd(dir_ + "/far.pcd", far);
  ExpectBadInput("--map " + dir_ + "/missing.pcd" + ref, "missing.pcd: cannot open");
  ExpectBadInput("--map " + dir_ + "/empty.pcd" + ref, "empty.pcd: empty file");
  ExpectBadInput("--map " + dir_ + "/nopoints.pcd" + ref, "nopoints.pcd: empty point cloud");
  ExpectBadInput("--map " + dir_ + "/nan.pcd" + ref, "nan.pcd: 1 of 100 points");
  ExpectBadInput("--map " + dir_ + "/far.pcd" + ref, "do not overlap");
  ExpectBadInput("--map " + dir_ + "/map.ply --ref-map " + dir_ + "/nan.pcd", "nan.pcd");
  ExpectBadInput("--map " + dir_ + "/map.ply", "needs both --map FILE and --ref-map FILE");
  ExpectBadInput("--map " + dir_ + "/map.ply" + ref + " --max-distance -1", "--max-distance");
  ExpectBadInput("--map " + dir_ + "/map.ply" + ref + " --gt x.tum", "cannot be combined");
}

}  // namespace
}  // namespace rvlio::testing_cli
