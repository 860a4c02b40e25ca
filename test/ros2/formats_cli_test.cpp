// End to end through the built tool: one simulated sequence written as a
// ROS1 bag, MCAP (zstd, lz4, uncompressed chunks, unchunked) and db3 gives
// byte-identical odometry outputs; `rvlio info` reads every kind.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../cli/cli_util.h"
#include "rvlio/io/recording.h"

namespace rvlio {
namespace {

using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

struct Format {
  const char* name;     // file stem
  const char* options;  // rvlio simulate options
  const char* file;     // written file
};
const std::vector<Format>& Formats() {
  static const std::vector<Format> formats = {
      {"ros1", "", "ros1.bag"},
      {"zstd", "--format mcap", "zstd.mcap"},
      {"lz4", "--format mcap --mcap-compression lz4", "lz4.mcap"},
      {"none", "--format mcap --mcap-compression none", "none.mcap"},
      {"unchunked", "--format mcap --mcap-compression unchunked", "unchunked.mcap"},
      {"db3", "--format db3", "db3.db3"},
  };
  return formats;
}

// A 4 s, 512-column tunnel, simulated once per format with the same seed.
class FormatsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_ros2");
    ASSERT_FALSE(dir_.empty());
    for (const Format& f : Formats()) {
      const ToolRun sim =
          RunTool(std::string("simulate --preset tunnel --seed 3 --duration 4 --out ") + dir_ +
                      " --set lidar.columns=512 --name " + f.name + " " + f.options,
                  dir_);
      ASSERT_EQ(sim.exit_code, 0) << f.name << ": " << sim.err;
    }
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static std::string Path(const std::string& file) { return dir_ + "/" + file; }
  static inline std::string dir_;
};

TEST_F(FormatsTest, EachFileIsDetectedAsItsKind) {
  const std::vector<RecordingKind> kinds = {RecordingKind::kRos1Bag, RecordingKind::kMcap,
                                            RecordingKind::kMcap,    RecordingKind::kMcap,
                                            RecordingKind::kMcap,    RecordingKind::kSqlite3};
  for (size_t i = 0; i < Formats().size(); ++i) {
    StatusOr<RecordingKind> kind = DetectRecording(Path(Formats()[i].file));
    ASSERT_TRUE(kind.ok()) << kind.status().message();
    EXPECT_EQ(*kind, kinds[i]) << Formats()[i].file;
  }
  // Content, not extension: a renamed MCAP is still an MCAP.
  std::filesystem::copy_file(Path("zstd.mcap"), Path("renamed.bag"));
  StatusOr<RecordingKind> kind = DetectRecording(Path("renamed.bag"));
  ASSERT_TRUE(kind.ok());
  EXPECT_EQ(*kind, RecordingKind::kMcap);
}

TEST_F(FormatsTest, RunGivesByteIdenticalOutputsOnEveryFormat) {
  std::string reference_tum, reference_map;
  for (const Format& f : Formats()) {
    const std::string out = Path(std::string("out_") + f.name);
    const ToolRun r = RunTool("run --quiet --bag " + Path(f.file) + " --config " +
                                  Path(std::string(f.name) + ".yaml") + " --out " + out,
                              dir_);
    ASSERT_EQ(r.exit_code, 0) << f.name << ": " << r.err;
    const std::string tum = ReadFile(out + "/trajectory.tum");
    const std::string map = ReadFile(out + "/map.pcd");
    ASSERT_GT(std::count(tum.begin(), tum.end(), '\n'), 20) << f.name;
    ASSERT_GT(map.size(), 1000u) << f.name;
    if (reference_tum.empty()) {
      reference_tum = tum;
      reference_map = map;
      continue;
    }
    EXPECT_TRUE(tum == reference_tum) << f.name << " trajectory.tum differs from the ROS1 run";
    EXPECT_TRUE(map == reference_map) << f.name << " map.pcd differs from the ROS1 run";
  }
}

TEST_F(FormatsTest, InfoNamesStorageCompressionAndLayout) {
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"ros1.bag", "storage:  ros1"},
      {"zstd.mcap", "compression: zstd"},
      {"lz4.mcap", "compression: lz4"},
      {"none.mcap", "compression: none"},
      {"unchunked.mcap", "storage:  mcap"},
      {"db3.db3", "storage:  sqlite3"},
  };
  for (const auto& [file, line] : expected) {
    const ToolRun r = RunTool("info --bag " + Path(file), dir_);
    ASSERT_EQ(r.exit_code, 0) << file << ": " << r.err;
    EXPECT_NE(r.out.find(line), std::string::npos) << file << ":\n" << r.out;
    EXPECT_NE(r.out.find("layout: ouster"), std::string::npos) << file << ":\n" << r.out;
    EXPECT_NE(r.out.find("points per scan:"), std::string::npos) << file << ":\n" << r.out;
  }
  const ToolRun r = RunTool("info --bag " + Path("unchunked.mcap"), dir_);
  EXPECT_EQ(r.out.find("compression:"), std::string::npos) << r.out;
  // The same counts everywhere: compare the topic lines of db3 and ROS1.
  const ToolRun ros1 = RunTool("info --bag " + Path("ros1.bag"), dir_);
  const ToolRun db3 = RunTool("info --bag " + Path("db3.db3"), dir_);
  auto topic_counts = [](const std::string& out) {
    std::vector<std::string> counts;
    for (size_t at = out.find(" msgs"); at != std::string::npos; at = out.find(" msgs", at + 1)) {
      const size_t begin = out.rfind(' ', at - 1);
      counts.push_back(out.substr(begin, at - begin));
    }
    return counts;
  };
  EXPECT_EQ(topic_counts(ros1.out), topic_counts(db3.out));
  EXPECT_EQ(topic_counts(ros1.out).size(), 2u);
}

}  // namespace
}  // namespace rvlio
