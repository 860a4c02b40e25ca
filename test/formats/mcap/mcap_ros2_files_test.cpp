// The MCAP reader on files written by the ROS 2 tools (test/data/ros2_bags,
// zstd and uncompressed chunks, ros2msg schemas): what each folder's
// metadata.yaml says must come out of the reader.
#include <map>
#include <string>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "mcap_test_util.h"
#include "rvlio/formats/mcap.h"

namespace rvlio {
namespace {

struct TopicSeen {
  uint64_t count = 0;
  std::vector<mcap::Message> messages;
};

class Ros2McapFile : public ::testing::TestWithParam<const char*> {};

TEST_P(Ros2McapFile, MatchesRosbag2Metadata) {
  const std::string dir = std::string(RVLIO_TEST_DATA) + "/ros2_bags/" + GetParam();
  const YAML::Node info = YAML::LoadFile(dir + "/metadata.yaml")["rosbag2_bagfile_information"];
  ASSERT_EQ(info["storage_identifier"].as<std::string>(), "mcap");
  const std::string path = dir + "/" + info["relative_file_paths"][0].as<std::string>();
  auto reader = mcap::Reader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  const mcap::FileSummary& summary = (*reader)->summary();
  EXPECT_EQ(summary.profile, "ros2");
  EXPECT_TRUE(summary.has_summary);
  EXPECT_FALSE(summary.truncated);
  EXPECT_TRUE((*reader)->warnings().empty());

  std::map<std::string, TopicSeen> topics;
  uint64_t total = 0, first = 0, last = 0;
  for (const mcap::Message& m : mcap_test::ReadAll(reader->get())) {
    if (total > 0) {
      EXPECT_GE(m.log_time_ns, last) << "not in log-time order";
    }
    if (total == 0) first = m.log_time_ns;
    last = m.log_time_ns;
    ++total;
    ASSERT_EQ((*reader)->channels().count(m.channel_id), 1u);
    TopicSeen& seen = topics[(*reader)->channels().at(m.channel_id).topic];
    ++seen.count;
    seen.messages.push_back(m);
  }
  EXPECT_EQ(total, info["message_count"].as<uint64_t>());
  EXPECT_EQ(summary.message_count, total);
  EXPECT_EQ(first, info["starting_time"]["nanoseconds_since_epoch"].as<uint64_t>());
  EXPECT_EQ(last - first, info["duration"]["nanoseconds"].as<uint64_t>());
  EXPECT_EQ(summary.message_start_time_ns, first);
  EXPECT_EQ(summary.message_end_time_ns, last);

  std::map<std::string, uint16_t> channel_of_topic;
  for (const auto& [id, channel] : (*reader)->channels()) channel_of_topic[channel.topic] = id;
  for (const YAML::Node& topic : info["topics_with_message_count"]) {
    const std::string name = topic["topic_metadata"]["name"].as<std::string>();
    const uint64_t count = topic["message_count"].as<uint64_t>();
    SCOPED_TRACE(name);
    EXPECT_EQ(topics[name].count, count);
    if (count == 0) continue;
    ASSERT_EQ(channel_of_topic.count(name), 1u);
    const mcap::Channel& channel = (*reader)->channels().at(channel_of_topic[name]);
    EXPECT_EQ(channel.message_encoding, topic["topic_metadata"]["serialization_format"].as<std::string>());
    ASSERT_EQ((*reader)->schemas().count(channel.schema_id), 1u);
    EXPECT_EQ((*reader)->schemas().at(channel.schema_id).name,
              topic["topic_metadata"]["type"].as<std::string>());
    EXPECT_EQ((*reader)->schemas().at(channel.schema_id).encoding, "ros2msg");
    EXPECT_EQ(summary.channel_message_counts.at(channel.id), count);
  }
  EXPECT_EQ(summary.chunk_count, 1u);
}

INSTANTIATE_TEST_SUITE_P(Rosbag2, Ros2McapFile,
                         ::testing::Values("mcap_talker", "mcap_cdr_test"));

// CDR std_msgs/msg/String: 4-byte encapsulation header, uint32 length
// (including the NUL), the characters, NUL.
std::string DecodeCdrString(const std::vector<uint8_t>& data) {
  if (data.size() < 8) return "<short>";
  const uint32_t length = static_cast<uint32_t>(mcap_test::Le(
      std::string(data.begin(), data.end()), 4, 4));
  if (length == 0 || length > data.size() - 8) return "<bad length>";
  return std::string(data.begin() + 8, data.begin() + 8 + length - 1);
}

TEST(Ros2McapTalker, TopicMessagesAreHelloWorldTexts) {
  const std::string path = std::string(RVLIO_TEST_DATA) + "/ros2_bags/mcap_talker/talker.mcap";
  auto reader = mcap::Reader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  EXPECT_EQ((*reader)->summary().compressions, std::vector<std::string>{"zstd"});
  uint16_t topic_channel = 0;
  for (const auto& [id, channel] : (*reader)->channels())
    if (channel.topic == "/topic") topic_channel = id;
  (*reader)->SetChannelFilter({topic_channel});
  std::vector<int> numbers;
  for (const mcap::Message& m : mcap_test::ReadAll(reader->get())) {
    ASSERT_EQ(m.channel_id, topic_channel);
    const std::string text = DecodeCdrString(m.data);
    ASSERT_EQ(text.rfind("Hello, world! ", 0), 0u) << text;
    numbers.push_back(std::stoi(text.substr(14)));
  }
  ASSERT_EQ(numbers.size(), 10u);
  for (size_t i = 1; i < numbers.size(); ++i) EXPECT_EQ(numbers[i], numbers[i - 1] + 1);
}

// The talker file cut short (no summary): the linear scan decompresses the
// zstd chunk when it is complete and returns nothing of a cut chunk.
TEST(Ros2McapTalker, CutFileIsReadByLinearScan) {
  const std::string bytes =
      mcap_test::ReadFile(std::string(RVLIO_TEST_DATA) + "/ros2_bags/mcap_talker/talker.mcap");
  const std::vector<mcap_test::TopRecord> records = mcap_test::WalkRecords(bytes, bytes.size());
  uint64_t chunk_end = 0;
  for (const auto& r : records)
    if (r.opcode == 0x06) chunk_end = r.end;
  ASSERT_GT(chunk_end, 0u);
  for (const uint64_t cut : {chunk_end - 1, chunk_end, bytes.size() - 40}) {
    SCOPED_TRACE(cut);
    auto reader = mcap::Reader::OpenBuffer(bytes.substr(0, cut), "talker_cut.mcap");
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    EXPECT_TRUE((*reader)->summary().truncated);
    EXPECT_FALSE((*reader)->summary().has_summary);
    ASSERT_FALSE((*reader)->warnings().empty());
    EXPECT_NE((*reader)->warnings()[0].find("talker_cut.mcap"), std::string::npos);
    const uint64_t expected = cut < chunk_end ? 0 : 20;
    EXPECT_EQ((*reader)->summary().message_count, expected);
    EXPECT_EQ(mcap_test::ReadAll(reader->get()).size(), expected);
    if (expected > 0) {
      EXPECT_EQ((*reader)->channels().size(), 3u);
    }
  }
}

}  // namespace
}  // namespace rvlio
