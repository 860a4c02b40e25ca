#pragma once
// Helpers of the MCAP tests: temporary files, a deterministic message set and
// an independent walk over a file's top-level records (the tests' own view
// of the layout, to know what a cut file still holds).
#include <stdlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/formats/mcap.h"

namespace rvlio::mcap_test {

inline std::string MakeTempDir() {
  std::string tmpl = std::filesystem::temp_directory_path().string() + "/rvlio_mcap_XXXXXX";
  if (::mkdtemp(tmpl.data()) == nullptr) return "";
  return tmpl;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

inline uint64_t Le(const std::string& b, size_t at, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= uint64_t{static_cast<uint8_t>(b[at + i])} << (8 * i);
  return v;
}

// Three channels, interleaved; every 7th message is stamped 35 ms earlier
// than its neighbours, so log times go backwards across chunk boundaries.
// Payload sizes vary; the bytes encode the index.
inline std::vector<mcap::Message> MakeMessages(int count = 600) {
  std::vector<mcap::Message> messages;
  for (int i = 0; i < count; ++i) {
    mcap::Message m;
    m.channel_id = static_cast<uint16_t>(i % 3);
    m.sequence = static_cast<uint32_t>(i);
    m.log_time_ns = 1'000'000'000ull + uint64_t(i) * 10'000'000ull - (i % 7 == 6 ? 35'000'000ull : 0);
    if (i % 50 == 10) m.log_time_ns = messages.back().log_time_ns;  // a tie
    m.publish_time_ns = m.log_time_ns - 1000;
    m.data.resize(20 + (i * 37) % 300);
    for (size_t k = 0; k < m.data.size(); ++k) m.data[k] = static_cast<uint8_t>(i * 31 + k);
    messages.push_back(std::move(m));
  }
  return messages;
}

// The write order sorted by log time, ties in write order: what a reader must return.
inline std::vector<mcap::Message> InLogTimeOrder(std::vector<mcap::Message> messages) {
  std::stable_sort(messages.begin(), messages.end(), [](const auto& a, const auto& b) {
    return a.log_time_ns < b.log_time_ns;
  });
  return messages;
}

// Writes `messages` on channels 0..2 (topics /a /b /c) to `path`.
inline Status WriteMessages(const std::string& path, const mcap::WriterOptions& options,
                            const std::vector<mcap::Message>& messages) {
  auto writer = mcap::Writer::Create(path, options);
  if (!writer.ok()) return writer.status();
  auto schema = (*writer)->AddSchema("test_msgs/msg/Blob", "ros2msg", "uint8[] data\n");
  if (!schema.ok()) return schema.status();
  for (const char* topic : {"/a", "/b", "/c"}) {
    auto channel = (*writer)->AddChannel(*schema, topic, "cdr");
    if (!channel.ok()) return channel.status();
  }
  for (const auto& m : messages)
    if (Status s = (*writer)->Write(m); !s.ok()) return s;
  return (*writer)->Close();
}

// Reads every message (fails the test on an error).
inline std::vector<mcap::Message> ReadAll(mcap::Reader* reader) {
  std::vector<mcap::Message> out;
  mcap::Message m;
  for (;;) {
    StatusOr<bool> more = reader->Next(&m);
    EXPECT_TRUE(more.ok()) << more.status().message();
    if (!more.ok() || !*more) break;
    out.push_back(m);
  }
  return out;
}

inline void ExpectSameMessages(const std::vector<mcap::Message>& expected,
                               const std::vector<mcap::Message>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(expected[i].channel_id, actual[i].channel_id) << i;
    EXPECT_EQ(expected[i].sequence, actual[i].sequence) << i;
    EXPECT_EQ(expected[i].log_time_ns, actual[i].log_time_ns) << i;
    EXPECT_EQ(expected[i].publish_time_ns, actual[i].publish_time_ns) << i;
    EXPECT_EQ(expected[i].data, actual[i].data) << i;
  }
}

// One top-level record of a file, as the tests see it.
struct TopRecord {
  uint8_t opcode = 0;
  uint64_t offset = 0, end = 0;
  uint64_t messages = 0;  // Message: 1; uncompressed Chunk: messages inside
  std::vector<uint16_t> channels;  // of those messages
};

// Top-level records from after the magic up to `size` bytes, stopping at the
// first record that does not fit. Messages inside chunks are counted for
// uncompressed chunks only (compression "").
inline std::vector<TopRecord> WalkRecords(const std::string& b, size_t size) {
  std::vector<TopRecord> records;
  size_t pos = 8;
  while (pos + 9 <= size) {
    TopRecord r;
    r.opcode = static_cast<uint8_t>(b[pos]);
    r.offset = pos;
    r.end = pos + 9 + Le(b, pos + 1, 8);
    if (r.end > size) break;
    if (r.opcode == 0x05) r.messages = 1;
    if (r.opcode == 0x06 && Le(b, pos + 9 + 28, 4) == 0) {  // compression ""
      for (size_t p = pos + 9 + 40; p < r.end; p += 9 + Le(b, p + 1, 8))
        if (b[p] == 0x05) {
          ++r.messages;
          r.channels.push_back(static_cast<uint16_t>(Le(b, p + 9, 2)));
        }
    }
    records.push_back(r);
    pos = r.end;
  }
  return records;
}

}  // namespace rvlio::mcap_test
