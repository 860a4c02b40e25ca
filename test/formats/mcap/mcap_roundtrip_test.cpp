// MCAP writer -> reader round trips, cut and corrupted files, the channel
// filter and bad input.
#include <signal.h>
#include <sys/resource.h>

#include <cstdio>
#include <filesystem>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "mcap_test_util.h"
#include "rvlio/formats/mcap.h"

namespace rvlio {
namespace {

using mcap_test::InLogTimeOrder;
using mcap_test::MakeMessages;
using mcap_test::ReadAll;
using mcap_test::ReadFile;
using mcap_test::TopRecord;
using mcap_test::WalkRecords;
using mcap_test::WriteFile;
using mcap_test::WriteMessages;

class McapTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = mcap_test::MakeTempDir();
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Writes MakeMessages() with `options`; returns the file's bytes.
  std::string Write(const mcap::WriterOptions& options, const std::string& name = "t.mcap") {
    const std::string path = dir_ + "/" + name;
    const Status s = WriteMessages(path, options, messages_);
    EXPECT_TRUE(s.ok()) << s.message();
    return ReadFile(path);
  }
  static mcap::WriterOptions Options(const std::string& compression, bool chunked = true) {
    mcap::WriterOptions options;
    options.compression = compression;
    options.chunked = chunked;
    options.chunk_size = 2000;  // a few messages per chunk: many chunks
    return options;
  }
  // The error of opening + reading everything ("" when both succeed).
  static std::string ReadError(const std::string& bytes, const std::string& name) {
    auto reader = mcap::Reader::OpenBuffer(bytes, name);
    if (!reader.ok()) return reader.status().message();
    mcap::Message m;
    for (;;) {
      StatusOr<bool> more = (*reader)->Next(&m);
      if (!more.ok()) return more.status().message();
      if (!*more) return "";
    }
  }

  std::string dir_;
  std::vector<mcap::Message> messages_ = MakeMessages();
};

struct RoundTripCase {
  const char* compression;
  bool chunked;
};

class McapRoundTrip : public McapTest, public ::testing::WithParamInterface<RoundTripCase> {};

TEST_P(McapRoundTrip, ReadsBackInLogTimeOrder) {
  const RoundTripCase c = GetParam();
  const std::string path = dir_ + "/t.mcap";
  Write(Options(c.compression, c.chunked));
  auto reader = mcap::Reader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  const mcap::FileSummary& summary = (*reader)->summary();
  EXPECT_TRUE(summary.has_summary);
  EXPECT_FALSE(summary.truncated);
  EXPECT_TRUE((*reader)->warnings().empty());
  EXPECT_EQ(summary.profile, "ros2");
  EXPECT_EQ(summary.library, "rvlio");
  EXPECT_EQ(summary.message_count, messages_.size());
  EXPECT_EQ(summary.channel_message_counts.at(0), 200u);
  EXPECT_EQ(summary.channel_message_counts.at(2), 200u);
  const std::vector<mcap::Message> expected = InLogTimeOrder(messages_);
  EXPECT_EQ(summary.message_start_time_ns, expected.front().log_time_ns);
  EXPECT_EQ(summary.message_end_time_ns, expected.back().log_time_ns);
  if (c.chunked) {
    EXPECT_GT(summary.chunk_count, 20u);
    EXPECT_EQ(summary.compressions, std::vector<std::string>{c.compression});
  } else {
    EXPECT_EQ(summary.chunk_count, 0u);
  }
  ASSERT_EQ((*reader)->channels().size(), 3u);
  EXPECT_EQ((*reader)->channels().at(1).topic, "/b");
  EXPECT_EQ((*reader)->channels().at(1).message_encoding, "cdr");
  EXPECT_EQ((*reader)->schemas().at(1).name, "test_msgs/msg/Blob");
  EXPECT_EQ((*reader)->schemas().at(1).data, "uint8[] data\n");
  mcap_test::ExpectSameMessages(expected, ReadAll(reader->get()));
  EXPECT_EQ((*reader)->chunks_loaded(), c.chunked ? summary.chunk_count : 0u);
  // No temporary file is left next to the output.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 1);
}

// SetTimeRange returns exactly the messages of the range (the full read,
// filtered), from the indexes and from a linear scan (no footer), and opens
// only the chunks whose time span meets the range.
TEST_P(McapRoundTrip, TimeRangeReturnsExactlyTheMessagesOfTheRange) {
  const RoundTripCase c = GetParam();
  const std::string written = Write(Options(c.compression, c.chunked));
  const std::vector<mcap::Message> all = InLogTimeOrder(messages_);
  const uint64_t t_a = all[100].log_time_ns, t_b = all[180].log_time_ns;  // exact stamps
  struct Range {
    uint64_t first, last;
  };
  const std::vector<Range> ranges = {{t_a, t_b},
                                     {t_a, t_a},
                                     {t_a + 1, t_a + 2},  // between two stamps: none
                                     {t_b, t_a},          // first > last: none
                                     {0, UINT64_MAX},
                                     {all.back().log_time_ns, UINT64_MAX},
                                     {0, all.front().log_time_ns}};
  for (const bool use_summary : {true, false}) {
    for (const Range& range : ranges) {
      SCOPED_TRACE(std::string(use_summary ? "indexed" : "linear scan") + " [" +
                   std::to_string(range.first) + ", " + std::to_string(range.last) + "]");
      std::string bytes = written;
      if (!use_summary) bytes.resize(bytes.size() - 30);  // no footer
      auto reader = mcap::Reader::OpenBuffer(bytes, "t.mcap");
      ASSERT_TRUE(reader.ok()) << reader.status().message();
      (*reader)->SetTimeRange(range.first, range.last);
      std::vector<mcap::Message> want;
      for (const mcap::Message& m : all)
        if (m.log_time_ns >= range.first && m.log_time_ns <= range.last) want.push_back(m);
      const std::vector<mcap::Message> got = ReadAll(reader->get());
      mcap_test::ExpectSameMessages(want, got);
      if (!c.chunked) continue;
      const uint64_t chunks = (*reader)->summary().chunk_count;
      if (want.empty() && range.first <= range.last && range.first > 0) {
        EXPECT_LE((*reader)->chunks_loaded(), 2u);  // at most the chunks around the gap
      }
      if (range.first == t_a && range.last == t_b) {
        EXPECT_GT((*reader)->chunks_loaded(), 0u);
        EXPECT_LT((*reader)->chunks_loaded(), chunks / 2);
      }
      if (range.first > range.last) {
        EXPECT_EQ((*reader)->chunks_loaded(), 0u);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, McapRoundTrip,
                         ::testing::Values(RoundTripCase{"", true}, RoundTripCase{"zstd", true},
                                           RoundTripCase{"lz4", true},
                                           RoundTripCase{"zstd", false}),
                         [](const auto& info) {
                           return std::string(info.param.chunked ? "chunked_" : "unchunked_") +
                                  (*info.param.compression ? info.param.compression : "none");
                         });

// The reader reuses its chunk buffers and hands the caller's previous
// message buffer back to be filled again: messages whose sizes jump between
// 0 bytes and 1 MB, in chunks that overlap in time (several open at once)
// and chunks read one after another, come back exactly, into one Message.
TEST_P(McapRoundTrip, ReusedBuffersGiveEveryMessageOfEverySize) {
  const RoundTripCase c = GetParam();
  const size_t sizes[] = {1 << 20, 0, 17, 300000, 1, 1 << 20, 64, 5};
  messages_ = MakeMessages(90);
  for (size_t i = 0; i < messages_.size(); ++i) {
    std::vector<uint8_t>& data = messages_[i].data;
    data.resize(sizes[i % 8]);
    for (size_t k = 0; k < data.size(); ++k) data[k] = static_cast<uint8_t>(i * 13 + k * 7);
  }
  mcap::WriterOptions options = Options(c.compression, c.chunked);
  options.chunk_size = 1 << 20;  // a few messages per chunk
  Write(options);
  auto reader = mcap::Reader::Open(dir_ + "/t.mcap");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  if (c.chunked) {
    EXPECT_GT((*reader)->summary().chunk_count, 10u);
  }
  mcap_test::ExpectSameMessages(InLogTimeOrder(messages_), ReadAll(reader->get()));
}

// Messages of complete records of a cut file: complete uncompressed chunks
// (chunked) or complete Message records (unchunked).
uint64_t CompleteMessages(const std::string& bytes, size_t cut) {
  uint64_t count = 0;
  for (const TopRecord& r : WalkRecords(bytes, cut)) {
    if (r.opcode == 0x0F) break;  // DataEnd
    count += r.messages;
  }
  return count;
}

TEST_F(McapTest, CutFilesReturnTheMessagesOfCompleteRecords) {
  for (const bool chunked : {true, false}) {
    const std::string bytes = Write(Options("", chunked));
    const std::vector<TopRecord> records = WalkRecords(bytes, bytes.size());
    std::vector<size_t> cuts;
    for (int k = 1; k <= 7; ++k) cuts.push_back(bytes.size() * k / 8);
    cuts.push_back(records[5].end);      // exactly at a record boundary
    cuts.push_back(records[5].end + 3);  // inside a record header
    cuts.push_back(bytes.size() - 10);   // inside the footer
    for (const size_t cut : cuts) {
      SCOPED_TRACE(std::string(chunked ? "chunked" : "unchunked") + " cut at " + std::to_string(cut));
      auto reader = mcap::Reader::OpenBuffer(bytes.substr(0, cut), "cut.mcap");
      ASSERT_TRUE(reader.ok()) << reader.status().message();
      EXPECT_TRUE((*reader)->summary().truncated);
      EXPECT_FALSE((*reader)->summary().has_summary);
      ASSERT_FALSE((*reader)->warnings().empty());
      EXPECT_NE((*reader)->warnings()[0].find("'cut.mcap'"), std::string::npos);
      const uint64_t expected = CompleteMessages(bytes, cut);
      EXPECT_EQ((*reader)->summary().message_count, expected);
      const std::vector<mcap::Message> read = ReadAll(reader->get());
      ASSERT_EQ(read.size(), expected);
      // Exactly the first `expected` written messages, in log-time order.
      const std::vector<mcap::Message> want = InLogTimeOrder(
          std::vector<mcap::Message>(messages_.begin(), messages_.begin() + expected));
      mcap_test::ExpectSameMessages(want, read);
    }
  }
}

TEST_F(McapTest, CorruptChunkIsACrcErrorNamingItsOffset) {
  for (const char* compression : {"", "zstd", "lz4"}) {
    SCOPED_TRACE(compression);
    std::string bytes = Write(Options(compression));
    const std::vector<TopRecord> records = WalkRecords(bytes, bytes.size());
    std::vector<uint64_t> chunks;
    for (const TopRecord& r : records)
      if (r.opcode == 0x06) chunks.push_back(r.offset);
    ASSERT_GT(chunks.size(), 3u);
    const uint64_t chunk = chunks[2];
    // Uncompressed: a payload byte. Compressed: the last byte of the frame
    // (literals or the end mark), then the decoder or the CRC objects.
    const uint64_t end = records[std::find_if(records.begin(), records.end(),
                                              [&](const TopRecord& r) { return r.offset == chunk; }) -
                                 records.begin()].end;
    const uint64_t at = *compression ? end - 5 : end - 3;
    bytes[at] = static_cast<char>(bytes[at] ^ 0x5A);
    const std::string error = ReadError(bytes, "bad.mcap");
    EXPECT_NE(error.find("'bad.mcap': chunk at offset " + std::to_string(chunk)), std::string::npos)
        << error;
    if (!*compression) {
      EXPECT_NE(error.find("CRC mismatch (stored 0x"), std::string::npos) << error;
    }
    EXPECT_EQ(error.find('\n'), std::string::npos);
    // The same file cut short (linear scan) fails the same way at open.
    const std::string cut_error = ReadError(bytes.substr(0, bytes.size() - 100), "bad.mcap");
    EXPECT_NE(cut_error.find("chunk at offset " + std::to_string(chunk)), std::string::npos)
        << cut_error;
  }
}

TEST_F(McapTest, UnknownCompressionIsNamed) {
  std::string bytes = Write(Options("zstd"));
  const std::vector<TopRecord> records = WalkRecords(bytes, bytes.size());
  ASSERT_EQ(records[1].opcode, 0x06);  // the first chunk, after the Header
  const size_t name_at = records[1].offset + 9 + 32;
  ASSERT_EQ(bytes.substr(name_at, 4), "zstd");
  bytes.replace(name_at, 4, "brot");
  const std::string error = ReadError(bytes, "x.mcap");
  EXPECT_NE(error.find("'x.mcap': chunk at offset " + std::to_string(records[1].offset) +
                       " uses unknown compression 'brot'"),
            std::string::npos)
      << error;
}

TEST_F(McapTest, CorruptDataSectionAndSummaryCrcs) {
  // Unchunked: the reader scans the data section and checks DataEnd's CRC.
  std::string bytes = Write(Options("", false));
  const std::vector<TopRecord> records = WalkRecords(bytes, bytes.size());
  bytes[records[10].end - 1] ^= 0x01;  // a payload byte of a message
  EXPECT_NE(ReadError(bytes, "u.mcap").find("data section CRC mismatch"), std::string::npos)
      << ReadError(bytes, "u.mcap");
  // Chunked: a byte of the summary section.
  bytes = Write(Options("zstd"));
  bytes[bytes.size() - 100] ^= 0x01;
  const std::string error = ReadError(bytes, "s.mcap");
  EXPECT_NE(error.find("'s.mcap': summary section at offset"), std::string::npos) << error;
  EXPECT_NE(error.find("CRC mismatch"), std::string::npos) << error;
}

TEST_F(McapTest, BadFilesAreOneLineErrorsNamingTheFile) {
  const std::string good = Write(Options("zstd"));
  std::string wrong_magic = good;
  wrong_magic[1] = 'X';
  const std::pair<std::string, std::string> cases[] = {
      {"", "too short"},
      {"hello", "too short"},
      {std::string(300, '\x42'), "bad magic"},
      {wrong_magic, "bad magic"},
      {good.substr(0, 20), "Header"},
      {good.substr(0, 8) + std::string(100, '\x07'), "expected the Header record"},
  };
  for (const auto& [bytes, what] : cases) {
    SCOPED_TRACE(what);
    const std::string path = dir_ + "/bad.mcap";
    WriteFile(path, bytes);
    auto reader = mcap::Reader::Open(path);
    ASSERT_FALSE(reader.ok());
    EXPECT_EQ(reader.status().code(), StatusCode::kInvalidInput);
    const std::string& message = reader.status().message();
    EXPECT_NE(message.find("'" + path + "'"), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  auto missing = mcap::Reader::Open(dir_ + "/missing.mcap");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("missing.mcap"), std::string::npos);
}

TEST_F(McapTest, ChannelFilterSkipsChunksWithoutWantedChannels) {
  // Channel 2 ("/c") only in the first 60 messages.
  std::vector<mcap::Message> messages;
  for (const mcap::Message& m : messages_)
    if (m.channel_id != 2 || m.sequence < 60) messages.push_back(m);
  messages_ = messages;
  const std::string path = dir_ + "/f.mcap";
  const std::string written = Write(Options(""), "f.mcap");
  uint64_t chunks_with_c = 0;
  for (const TopRecord& r : WalkRecords(written, written.size()))
    chunks_with_c += std::count(r.channels.begin(), r.channels.end(), 2) > 0 ? 1 : 0;
  ASSERT_GT(chunks_with_c, 0u);
  for (const bool use_summary : {true, false}) {
    SCOPED_TRACE(use_summary ? "indexed" : "linear scan");
    std::string bytes = ReadFile(path);
    if (!use_summary) bytes.resize(bytes.size() - 30);  // no footer
    auto reader = mcap::Reader::OpenBuffer(bytes, "f.mcap");
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    (*reader)->SetChannelFilter({2});
    std::vector<mcap::Message> want;
    for (const mcap::Message& m : InLogTimeOrder(messages_))
      if (m.channel_id == 2) want.push_back(m);
    mcap_test::ExpectSameMessages(want, ReadAll(reader->get()));
    EXPECT_GT((*reader)->summary().chunk_count, 20u);
    EXPECT_EQ((*reader)->chunks_loaded(), chunks_with_c);
  }
}

TEST_F(McapTest, WriterWithoutCloseLeavesNoFile) {
  const std::string path = dir_ + "/gone.mcap";
  {
    auto writer = mcap::Writer::Create(path, Options("lz4"));
    ASSERT_TRUE(writer.ok());
    auto schema = (*writer)->AddSchema("s", "ros2msg", "");
    ASSERT_TRUE(schema.ok());
    auto channel = (*writer)->AddChannel(*schema, "/a", "cdr");
    ASSERT_TRUE(channel.ok());
    for (const mcap::Message& m : messages_) {
      mcap::Message copy = m;
      copy.channel_id = *channel;
      ASSERT_TRUE((*writer)->Write(copy).ok());
    }
    EXPECT_FALSE((*writer)->Write(mcap::Message{7, 0, 0, 0, {}}).ok());  // unknown channel
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 0);
  EXPECT_FALSE(mcap::Writer::Create(path, Options("brotli")).ok());
  auto unwritable = mcap::Writer::Create(dir_ + "/no/such/dir/x.mcap", Options("zstd"));
  ASSERT_FALSE(unwritable.ok());
  EXPECT_NE(unwritable.status().message().find("x.mcap"), std::string::npos);
}

// A write that fails half way (here: the file size limit, as a full disk
// would) is a Status naming the file, and no file, half or temporary, remains.
TEST_F(McapTest, FailedWriteLeavesNoFile) {
  std::vector<mcap::Message> big(20);
  for (size_t i = 0; i < big.size(); ++i) {
    big[i].channel_id = static_cast<uint16_t>(i % 3);
    big[i].log_time_ns = i;
    big[i].data.assign(200000, static_cast<uint8_t>(i));
  }
  const std::string path = dir_ + "/full.mcap";
  struct rlimit saved {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  void (*saved_handler)(int) = ::signal(SIGXFSZ, SIG_IGN);  // write() fails with EFBIG instead
  struct rlimit limited = saved;
  limited.rlim_cur = 256 << 10;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  const Status s = WriteMessages(path, Options(""), big);
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::signal(SIGXFSZ, saved_handler);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("full.mcap"), std::string::npos) << s.message();
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_), {}), 0);
}

}  // namespace
}  // namespace rvlio
