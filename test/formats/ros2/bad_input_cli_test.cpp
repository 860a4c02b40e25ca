// Bad ROS 2 input through the built tool: each case exits 2 with one line
// naming the file and what is wrong, and leaves an existing output folder as
// it was; a cut-short MCAP is read up to its last complete chunk, with a warning.
#include <sqlite3.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;
using testing_cli::ReadFile;
using testing_cli::RunTool;
using testing_cli::ToolRun;

void WriteAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

uint64_t U64At(const std::string& b, size_t at) {
  uint64_t v = 0;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}

// Byte offset of the first Chunk record (opcode 0x06) of an MCAP file.
size_t FirstChunk(const std::string& mcap) {
  size_t pos = 8;  // after the magic
  while (pos + 9 <= mcap.size()) {
    if (static_cast<uint8_t>(mcap[pos]) == 0x06) return pos;
    pos += 9 + U64At(mcap, pos + 1);
  }
  return std::string::npos;
}

// Chunk content: start, end, uncompressed_size (3 x u64), uncompressed_crc
// (u32), compression (u32 length + bytes), records (u64 length + bytes).
size_t CompressionAt(size_t chunk) { return chunk + 9 + 8 * 3 + 4; }

class BadRos2InputTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_ros2_bad");
    ASSERT_FALSE(dir_.empty());
    for (const char* args : {"--format mcap --name zstd", "--format mcap --mcap-compression none --name none",
                             "--format db3 --name seq"}) {
      const ToolRun sim = testing_cli::SimulateTunnel(dir_, 3, 4, dir_, args);
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return dir_ + "/" + name; }

  // `rvlio run` into an output folder that already holds a file: a failed
  // run must leave it alone.
  static ToolRun RunInto(const std::string& bag, const std::string& extra = "") {
    const std::string out = Path("out");
    fs::remove_all(out);
    fs::create_directories(out);
    WriteAll(out + "/keep.txt", "earlier result\n");
    ToolRun r = RunTool("run --quiet --bag " + bag + " --config " + Path("seq.yaml") + " --out " +
                            out + " " + extra,
                        dir_);
    EXPECT_EQ(ReadFile(out + "/keep.txt"), "earlier result\n") << bag;
    return r;
  }

  static void ExpectOneLineError(const ToolRun& r, const std::string& file,
                                 const std::string& problem) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("rvlio run: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(problem), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(Path("out/trajectory.tum"))) << r.err;
  }

  static inline std::string dir_;
};

TEST_F(BadRos2InputTest, CutShortMcapIsReadUpToItsLastCompleteChunkWithAWarning) {
  const std::string bytes = ReadFile(Path("zstd.mcap"));
  const std::string cut = Path("cut.mcap");
  WriteAll(cut, bytes.substr(0, bytes.size() * 6 / 10));
  const ToolRun full = RunTool("run --quiet --bag " + Path("zstd.mcap") + " --config " +
                                   Path("seq.yaml") + " --out " + Path("out_full"), dir_);
  ASSERT_EQ(full.exit_code, 0) << full.err;
  const ToolRun r = RunTool("run --quiet --bag " + cut + " --config " + Path("seq.yaml") +
                                " --out " + Path("out_cut"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("rvlio run: warning: '" + cut + "'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cut short"), std::string::npos) << r.err;
  const std::string tum_full = ReadFile(Path("out_full/trajectory.tum"));
  const std::string tum_cut = ReadFile(Path("out_cut/trajectory.tum"));
  const auto poses = [](const std::string& t) { return std::count(t.begin(), t.end(), '\n'); };
  EXPECT_GT(poses(tum_cut), 5);
  EXPECT_LT(poses(tum_cut), poses(tum_full));
  // What was read is what the complete file gives for the same span.
  EXPECT_EQ(tum_full.compare(0, tum_cut.size() / 2, tum_cut, 0, tum_cut.size() / 2), 0);
  const ToolRun info = RunTool("info --bag " + cut, dir_);
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.err.find("rvlio info: warning: '" + cut + "'"), std::string::npos) << info.err;
}

TEST_F(BadRos2InputTest, ChunkCrcMismatchNamesTheChunkOffset) {
  std::string bytes = ReadFile(Path("none.mcap"));
  const size_t chunk = FirstChunk(bytes);
  ASSERT_NE(chunk, std::string::npos);
  uint32_t compression_length = 0;
  std::memcpy(&compression_length, bytes.data() + CompressionAt(chunk), 4);
  const size_t records = CompressionAt(chunk) + 4 + compression_length + 8;
  bytes[records + 5000] ^= 0x5a;  // inside a message payload of the first chunk
  const std::string bad = Path("crc.mcap");
  WriteAll(bad, bytes);
  const ToolRun r = RunInto(bad);
  ExpectOneLineError(r, bad, "chunk at offset " + std::to_string(chunk));
  EXPECT_NE(r.err.find("CRC mismatch"), std::string::npos) << r.err;
}

TEST_F(BadRos2InputTest, UnknownChunkCompressionIsNamed) {
  std::string bytes = ReadFile(Path("zstd.mcap"));
  const size_t chunk = FirstChunk(bytes);
  ASSERT_NE(chunk, std::string::npos);
  ASSERT_EQ(bytes.substr(CompressionAt(chunk) + 4, 4), "zstd");
  bytes.replace(CompressionAt(chunk) + 4, 4, "brot");
  const std::string bad = Path("brot.mcap");
  WriteAll(bad, bytes);
  ExpectOneLineError(RunInto(bad), bad, "unknown compression 'brot'");
}

TEST_F(BadRos2InputTest, UnknownMessageTypeOnTheChosenTopic) {
  const std::string talker = std::string(RVLIO_TEST_DATA) + "/ros2_bags/sqlite3_talker";
  ExpectOneLineError(RunInto(talker, "--set lidar.topic=/topic"), talker,
                     "lidar.topic '/topic' in bag '" + talker +
                         "' has type std_msgs/msg/String, expected sensor_msgs/msg/PointCloud2");
}

TEST_F(BadRos2InputTest, Db3WithoutTheTopicListsTheTopicsPresent) {
  const ToolRun r = RunInto(Path("seq.db3"), "--set imu.topic=/imu/missing");
  ExpectOneLineError(r, Path("seq.db3"), "imu.topic '/imu/missing' is not in bag");
  EXPECT_NE(r.err.find("topics present: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(sensor_msgs/msg/Imu)"), std::string::npos) << r.err;
}

TEST_F(BadRos2InputTest, EmptyFolderAndMetadataNamingAMissingFile) {
  const std::string empty = Path("empty_folder");
  fs::create_directories(empty);
  ExpectOneLineError(RunInto(empty), empty, "is an empty directory");

  const std::string folder = Path("no_db3");
  fs::create_directories(folder);
  fs::copy_file(std::string(RVLIO_TEST_DATA) + "/ros2_bags/sqlite3_talker/metadata.yaml",
                folder + "/metadata.yaml");
  ExpectOneLineError(RunInto(folder), folder + "/metadata.yaml",
                     "names file 'talker.db3', which does not exist");
}

TEST_F(BadRos2InputTest, CdrSequenceLongerThanItsMessage) {
  const std::string bad = Path("short_cloud.db3");
  fs::copy_file(Path("seq.db3"), bad, fs::copy_options::overwrite_existing);
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(bad.c_str(), &db), SQLITE_OK);
  // The first cloud loses its last 1000 bytes: its data sequence still
  // claims every byte.
  const char* sql =
      "UPDATE messages SET data = substr(data, 1, length(data) - 1000) WHERE id = "
      "(SELECT MIN(m.id) FROM messages m JOIN topics t ON m.topic_id = t.id "
      "WHERE t.type = 'sensor_msgs/msg/PointCloud2')";
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  EXPECT_EQ(sqlite3_changes(db), 1);
  sqlite3_close(db);
  const ToolRun r = RunInto(bad);
  ExpectOneLineError(r, bad, "field 'data'");
  EXPECT_NE(r.err.find("sequence length"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("sensor_msgs/msg/PointCloud2"), std::string::npos) << r.err;
}

TEST_F(BadRos2InputTest, FileOfNoKnownKind) {
  const std::string text = Path("notes.txt");
  WriteAll(text, "neither a bag nor a database\n");
  ExpectOneLineError(RunInto(text), text, "is not a recording rvlio reads");
  const ToolRun info = RunTool("info --bag " + text, dir_);
  EXPECT_EQ(info.exit_code, 2);
  EXPECT_EQ(Lines(info.err), 1) << info.err;
}

}  // namespace
}  // namespace rvlio
