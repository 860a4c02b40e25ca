// The four bags of test/data/ros2_bags were written by the ROS 2 tools
// (rosbag2), not by rvlio: the reader must reproduce what each bag's
// metadata.yaml says (topics, types, counts, starting time, duration) and
// decode the talker's std_msgs/msg/String messages, for both storages.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "rvlio/formats/cdr.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

std::string Folder(const std::string& name) {
  return std::string(RVLIO_TEST_DATA) + "/ros2_bags/" + name;
}

struct ExpectedTopic {
  std::string type;
  int64_t count = 0;
};
struct Expected {
  std::string storage;
  std::vector<std::string> files;
  TimeNs start_ns = 0, duration_ns = 0;
  int64_t messages = 0;
  std::map<std::string, ExpectedTopic> topics;
};

// What rosbag2 wrote into metadata.yaml.
Expected ReadMetadata(const std::string& folder) {
  const YAML::Node info = YAML::LoadFile(folder + "/metadata.yaml")["rosbag2_bagfile_information"];
  Expected e;
  e.storage = info["storage_identifier"].as<std::string>();
  for (const auto& f : info["relative_file_paths"]) e.files.push_back(f.as<std::string>());
  e.start_ns = info["starting_time"]["nanoseconds_since_epoch"].as<int64_t>();
  e.duration_ns = info["duration"]["nanoseconds"].as<int64_t>();
  e.messages = info["message_count"].as<int64_t>();
  for (const auto& t : info["topics_with_message_count"]) {
    const YAML::Node meta = t["topic_metadata"];
    e.topics[meta["name"].as<std::string>()] = {meta["type"].as<std::string>(),
                                                t["message_count"].as<int64_t>()};
  }
  return e;
}

// Reads every message of `path` and checks it against the metadata.
void CheckAgainstMetadata(const std::string& path, const Expected& e) {
  SCOPED_TRACE(path);
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  ASSERT_TRUE(source.ok()) << source.status().message();
  EXPECT_EQ((*source)->storage(), e.storage);
  const auto& topics = (*source)->topics();
  std::map<std::string, int64_t> counts;
  for (const RecordingTopic& t : topics) {
    auto it = e.topics.find(t.name);
    ASSERT_NE(it, e.topics.end()) << t.name << " is not in metadata.yaml";
    EXPECT_EQ(t.type, it->second.type) << t.name;
    EXPECT_EQ(t.serialization_format, "cdr") << t.name;
    counts[t.name] = 0;
  }
  RawMessage m;
  TimeNs first = 0, last = 0, previous = 0;
  int64_t n = 0;
  while (true) {
    StatusOr<bool> got = (*source)->Next(&m);
    ASSERT_TRUE(got.ok()) << got.status().message();
    if (!*got) break;
    ASSERT_GE(m.topic, 0);
    ASSERT_LT(m.topic, static_cast<int>(topics.size()));
    ++counts[topics[m.topic].name];
    if (n == 0) first = m.stamp_ns;
    EXPECT_GE(m.stamp_ns, previous) << "message " << n << " out of time order";
    previous = last = m.stamp_ns;
    ++n;
  }
  EXPECT_EQ(n, e.messages);
  EXPECT_EQ(first, e.start_ns);
  EXPECT_EQ(last - first, e.duration_ns);
  for (const auto& [name, want] : e.topics) {
    if (want.count == 0 && counts.count(name) == 0) continue;  // a topic without messages
    EXPECT_EQ(counts[name], want.count) << name;
  }

  // The per-topic pass that `rvlio info` uses agrees.
  StatusOr<std::vector<RecordingTopicStats>> stats = (*source)->TopicStats();
  ASSERT_TRUE(stats.ok()) << stats.status().message();
  for (size_t i = 0; i < topics.size(); ++i)
    EXPECT_EQ((*stats)[i].count, counts[topics[i].name]) << topics[i].name;
}

class FixtureBagTest : public ::testing::TestWithParam<const char*> {};

TEST_P(FixtureBagTest, ReproducesMetadataAsFolderAndAsSingleFile) {
  const std::string folder = Folder(GetParam());
  const Expected e = ReadMetadata(folder);
  StatusOr<RecordingKind> kind = DetectRecording(folder);
  ASSERT_TRUE(kind.ok()) << kind.status().message();
  EXPECT_EQ(*kind, RecordingKind::kRos2Folder);
  CheckAgainstMetadata(folder, e);
  ASSERT_EQ(e.files.size(), 1u);
  const std::string file = folder + "/" + e.files[0];
  kind = DetectRecording(file);
  ASSERT_TRUE(kind.ok()) << kind.status().message();
  EXPECT_EQ(*kind, e.storage == "mcap" ? RecordingKind::kMcap : RecordingKind::kSqlite3);
  CheckAgainstMetadata(file, e);
}

TEST_P(FixtureBagTest, InfoReportsStorageTopicsAndSpan) {
  const std::string folder = Folder(GetParam());
  const Expected e = ReadMetadata(folder);
  StatusOr<BagInfo> info = ReadBagInfo(folder);
  ASSERT_TRUE(info.ok()) << info.status().message();
  EXPECT_EQ(info->storage, e.storage);
  EXPECT_EQ(info->messages, e.messages);
  EXPECT_EQ(info->start_ns, e.start_ns);
  EXPECT_EQ(info->end_ns - info->start_ns, e.duration_ns);
  // The cheap span (indexes and summary only) agrees.
  StatusOr<BagInfo> span = ReadBagSpan(folder);
  ASSERT_TRUE(span.ok()) << span.status().message();
  EXPECT_EQ(span->storage, e.storage);
  EXPECT_EQ(span->messages, e.messages);
  EXPECT_EQ(span->start_ns, e.start_ns);
  EXPECT_EQ(span->end_ns - span->start_ns, e.duration_ns);
  for (const BagTopicInfo& t : info->topics) {
    ASSERT_EQ(e.topics.count(t.topic), 1u) << t.topic;
    EXPECT_EQ(t.type, e.topics.at(t.topic).type);
    EXPECT_EQ(t.count, e.topics.at(t.topic).count) << t.topic;
    EXPECT_TRUE(t.lidar_layout.empty()) << t.topic;
  }
  // The talker's chunks are zstd-compressed, cdr_test's are not (checked
  // with `grep -c zstd` on the files: 2 and 0 hits).
  const std::map<std::string, std::vector<std::string>> compressions = {
      {"mcap_talker", {"zstd"}}, {"mcap_cdr_test", {"none"}}};
  auto it = compressions.find(GetParam());
  EXPECT_EQ(info->compressions,
            it == compressions.end() ? std::vector<std::string>() : it->second);
}

INSTANTIATE_TEST_SUITE_P(Ros2Bags, FixtureBagTest,
                         ::testing::Values("sqlite3_talker", "mcap_talker", "sqlite3_cdr_test",
                                           "mcap_cdr_test"));

class TalkerTest : public ::testing::TestWithParam<const char*> {};

TEST_P(TalkerTest, DecodesTheHelloWorldStrings) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(Folder(GetParam()));
  ASSERT_TRUE(source.ok()) << source.status().message();
  int topic = -1;
  for (size_t i = 0; i < (*source)->topics().size(); ++i) {
    if ((*source)->topics()[i].name == "/topic") topic = static_cast<int>(i);
  }
  ASSERT_GE(topic, 0);
  ASSERT_EQ((*source)->topics()[topic].type, cdr::kStringType);
  ASSERT_TRUE((*source)->SetTopicFilter({topic}).ok());
  std::vector<std::string> texts;
  RawMessage m;
  while (true) {
    StatusOr<bool> got = (*source)->Next(&m);
    ASSERT_TRUE(got.ok()) << got.status().message();
    if (!*got) break;
    ASSERT_EQ(m.topic, topic);
    StatusOr<std::string> text = cdr::DecodeString(m.data.data(), m.data.size(), "/topic");
    ASSERT_TRUE(text.ok()) << text.status().message();
    texts.push_back(*text);
  }
  ASSERT_EQ(texts.size(), 10u);
  for (size_t i = 0; i < texts.size(); ++i)
    EXPECT_EQ(texts[i], "Hello, world! " + std::to_string(i));
}

INSTANTIATE_TEST_SUITE_P(Ros2Bags, TalkerTest, ::testing::Values("sqlite3_talker", "mcap_talker"));

}  // namespace
}  // namespace rvlio
