// ReadMapPcd (outputs/run_outputs.h), which `rvlio merge` uses on the chunks'
// maps: reads back what WriteMapPcd wrote, and refuses truncated, lying or
// foreign files with InvalidInput naming the file instead of crashing or
// allocating what the header claims.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "rvlio/outputs/run_outputs.h"

namespace rvlio {
namespace {

class MapPcdTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rvlio_map_pcd_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(MapPcdTest, ReadsBackWhatWriteMapPcdWrote) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 1000; ++i) points.emplace_back(0.25 * i, -1.5 + i, 3.0 / (i + 1));
  ASSERT_TRUE(WriteMapPcd(Path("map.pcd"), points).ok());
  StatusOr<std::vector<Eigen::Vector3d>> read = ReadMapPcd(Path("map.pcd"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  ASSERT_EQ(read->size(), points.size());
  for (size_t i = 0; i < points.size(); ++i)
    EXPECT_TRUE((*read)[i].isApprox(points[i].cast<float>().cast<double>(), 1e-12)) << i;
  ASSERT_TRUE(WriteMapPcd(Path("empty.pcd"), {}).ok());
  read = ReadMapPcd(Path("empty.pcd"));
  ASSERT_TRUE(read.ok()) << read.status().message();
  EXPECT_TRUE(read->empty());
}

TEST_F(MapPcdTest, OtherTruncatedOrLyingFilesAreInvalidInput) {
  ASSERT_TRUE(WriteMapPcd(Path("map.pcd"), {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6)}).ok());
  std::ifstream in(Path("map.pcd"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string header = bytes.substr(0, bytes.size() - 24);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(Path(name), std::ios::binary) << text;
    return Path(name);
  };
  std::string lying = header;
  lying.replace(lying.find("POINTS 2"), 8, "POINTS 999999999999");
  // An ASCII header that claims more points than its bytes can hold.
  const std::string ascii = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 99999999999\nDATA ascii\n1 2 3\n";
  for (const std::string& path :
       {write("truncated.pcd", bytes.substr(0, bytes.size() - 5)), write("lying.pcd", lying),
        write("ascii.pcd", ascii), write("garbage.pcd", "not a pcd"), Path("missing.pcd")}) {
    StatusOr<std::vector<Eigen::Vector3d>> read = ReadMapPcd(path);
    ASSERT_FALSE(read.ok()) << path;
    EXPECT_EQ(read.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(read.status().message().find(path), std::string::npos) << read.status().message();
  }
}

}  // namespace
}  // namespace rvlio
