// fuzz/corpus/mcap/: the seed corpus of fuzz/mcap_fuzzer.cpp, tiny files of
// the writer (chunks none/zstd/lz4, unchunked, one cut short). Refresh with
//   RVLIO_WRITE_MCAP_SEEDS=1 build/bin/test_mcap --gtest_filter=McapFuzzSeeds.*
// Without the variable the test checks that every committed seed reads back
// as the messages it was made from.
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "mcap_test_util.h"
#include "rvlio/formats/mcap.h"

namespace rvlio {
namespace {

struct SeedSpec {
  const char* name;
  const char* compression;
  bool chunked;
  bool cut;  // cut in the middle of the data section (no summary, no footer)
};

constexpr SeedSpec kSeeds[] = {
    {"chunked_none.mcap", "", true, false},   {"chunked_zstd.mcap", "zstd", true, false},
    {"chunked_lz4.mcap", "lz4", true, false}, {"unchunked.mcap", "", false, false},
    {"truncated.mcap", "", true, true},
};

std::vector<mcap::Message> SeedMessages() {
  std::vector<mcap::Message> messages = mcap_test::MakeMessages(7);
  for (auto& m : messages) m.data.resize(8);
  return messages;
}

TEST(McapFuzzSeeds, CommittedSeedsReadBack) {
  const std::string corpus = std::string(RVLIO_SOURCE_DIR) + "/fuzz/corpus/mcap";
  const bool rewrite = std::getenv("RVLIO_WRITE_MCAP_SEEDS") != nullptr;
  const std::vector<mcap::Message> messages = SeedMessages();
  const std::string scratch = mcap_test::MakeTempDir();
  for (const SeedSpec& spec : kSeeds) {
    SCOPED_TRACE(spec.name);
    const std::string path = corpus + "/" + spec.name;
    if (rewrite) {
      mcap::WriterOptions options;
      options.compression = spec.compression;
      options.chunked = spec.chunked;
      options.chunk_size = 120;
      const std::string full = scratch + "/" + spec.name;
      ASSERT_TRUE(mcap_test::WriteMessages(full, options, messages).ok());
      std::string bytes = mcap_test::ReadFile(full);
      if (spec.cut) bytes.resize(bytes.size() / 2);
      std::filesystem::create_directories(corpus);
      mcap_test::WriteFile(path, bytes);
    }
    const std::string bytes = mcap_test::ReadFile(path);
    ASSERT_FALSE(bytes.empty()) << "missing seed " << path;
    EXPECT_LT(bytes.size(), 4096u);
    auto reader = mcap::Reader::Open(path);
    ASSERT_TRUE(reader.ok()) << reader.status().message();
    EXPECT_EQ((*reader)->summary().truncated, spec.cut);
    uint64_t expected = messages.size();
    if (spec.cut) {
      expected = 0;
      for (const auto& r : mcap_test::WalkRecords(bytes, bytes.size())) expected += r.messages;
      EXPECT_GT(expected, 0u);
      EXPECT_LT(expected, messages.size());
    }
    const std::vector<mcap::Message> read = mcap_test::ReadAll(reader->get());
    EXPECT_EQ(read.size(), expected);
  }
  std::filesystem::remove_all(scratch);
}

// Found by fuzz/mcap_fuzzer.cpp: a chunk's compression name holding a newline
// made the "unknown compression" error two lines; names are now escaped.
TEST(McapFuzzRegress, CompressionNameWithNewlineIsEscaped) {
  const std::string path =
      std::string(RVLIO_SOURCE_DIR) + "/fuzz/corpus/mcap/regress_newline_in_compression";
  auto reader = mcap::Reader::OpenBuffer(mcap_test::ReadFile(path), "n.mcap");
  ASSERT_FALSE(reader.ok());
  const std::string& message = reader.status().message();
  EXPECT_EQ(message.rfind("'n.mcap': chunk at offset 34 uses unknown compression 'msgs/msg/Blob", 0),
            0u)
      << message;
  EXPECT_NE(message.find("\\x"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

}  // namespace
}  // namespace rvlio
