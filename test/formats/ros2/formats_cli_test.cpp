// End to end through the built tool: one simulated sequence written as a
// ROS1 bag, MCAP (zstd, lz4, uncompressed chunks, unchunked) and db3 gives
// byte-identical odometry outputs, and so does its Livox CustomMsg version as
// ROS1, MCAP and db3; `rvlio info` reads every kind.
#include <sqlite3.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/recording.h"

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

// The same sequence with Livox CustomMsg scans (livox_ros_driver/CustomMsg in
// ROS1, livox_ros_driver2/msg/CustomMsg in ROS 2).
const std::vector<Format>& LivoxFormats() {
  static const std::vector<Format> formats = {
      {"livox_ros1", "--lidar-msg livox", "livox_ros1.bag"},
      {"livox_mcap", "--lidar-msg livox --format mcap", "livox_mcap.mcap"},
      {"livox_db3", "--lidar-msg livox --format db3", "livox_db3.db3"},
  };
  return formats;
}

// A 4 s, 512-column tunnel, simulated once per format with the same seed.
class FormatsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_ros2");
    ASSERT_FALSE(dir_.empty());
    std::vector<Format> all = Formats();
    all.insert(all.end(), LivoxFormats().begin(), LivoxFormats().end());
    for (const Format& f : all) {
      const ToolRun sim =
          testing_cli::SimulateTunnel(dir_, 3, 4, dir_, "--name " + std::string(f.name) + " " + f.options);
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

// `rvlio run` on each file; every output equals the first one's.
void ExpectIdenticalRuns(const std::vector<Format>& formats, const std::string& dir) {
  std::string reference_tum, reference_map;
  for (const Format& f : formats) {
    const std::string out = dir + "/out_" + f.name;
    const ToolRun r = RunTool("run --quiet --bag " + dir + "/" + f.file + " --config " + dir +
                                  "/" + f.name + ".yaml --out " + out,
                              dir);
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

TEST_F(FormatsTest, RunGivesByteIdenticalOutputsOnEveryFormat) { ExpectIdenticalRuns(Formats(), dir_); }

TEST_F(FormatsTest, LivoxCustomMsgRunsAreByteIdenticalAcrossRos1McapAndDb3) {
  ExpectIdenticalRuns(LivoxFormats(), dir_);
  for (const char* file : {"livox_mcap.mcap", "livox_db3.db3"}) {
    const ToolRun r = RunTool("info --bag " + Path(file), dir_);
    ASSERT_EQ(r.exit_code, 0) << file << ": " << r.err;
    EXPECT_NE(r.out.find("livox_ros_driver2/msg/CustomMsg"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("layout: livox_custom"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("points per scan:"), std::string::npos) << r.out;
  }
}

// The db3 split at its middle into two files of a bag folder (as `ros2 bag
// record --max-bag-duration` would write it), listed out of order in
// metadata.yaml's relative_file_paths: the folder reads as the whole db3.
TEST_F(FormatsTest, SplitBagFolderReadsAsTheWholeRecording) {
  const std::string folder = Path("split");
  std::filesystem::create_directories(folder);
  const char* keep[2] = {"timestamp < 1700000002000000000", "timestamp >= 1700000002000000000"};
  for (int i = 0; i < 2; ++i) {
    const std::string part = folder + "/split_" + std::to_string(i) + ".db3";
    std::filesystem::copy_file(Path("db3.db3"), part);
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(part.c_str(), &db), SQLITE_OK);
    const std::string sql = std::string("DELETE FROM messages WHERE NOT (") + keep[i] + ")";
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    EXPECT_GT(sqlite3_changes(db), 100);
    sqlite3_close(db);
  }
  std::ofstream(folder + "/metadata.yaml") << "rosbag2_bagfile_information:\n"
                                              "  version: 5\n"
                                              "  storage_identifier: sqlite3\n"
                                              "  relative_file_paths:\n"
                                              "    - split_1.db3\n"
                                              "    - split_0.db3\n";
  const std::string out = Path("out_split");
  const ToolRun r = RunTool("run --quiet --bag " + folder + " --config " + Path("db3.yaml") +
                                " --out " + out, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ToolRun whole = RunTool("run --quiet --bag " + Path("db3.db3") + " --config " +
                                    Path("db3.yaml") + " --out " + Path("out_whole"), dir_);
  ASSERT_EQ(whole.exit_code, 0) << whole.err;
  EXPECT_TRUE(ReadFile(out + "/trajectory.tum") == ReadFile(Path("out_whole/trajectory.tum")));
  EXPECT_TRUE(ReadFile(out + "/map.pcd") == ReadFile(Path("out_whole/map.pcd")));
  const ToolRun info = RunTool("info --bag " + folder, dir_);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("messages: 841"), std::string::npos) << info.out;
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
