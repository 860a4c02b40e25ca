// CRC-32 of src/formats/mcap_records.h (libdeflate) against known values: the
// standard check value, values from python3's zlib.crc32 for every length
// class the vectorized paths take, and the chunk CRC that the ROS 2 tools'
// MCAP writer stored in the talker fixture.
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "../src/formats/mcap_records.h"
#include "mcap_test_util.h"

namespace rvlio {
namespace {

using mcap::detail::Crc32;
using mcap::detail::Crc32Update;

TEST(McapCrc32, KnownValues) {
  EXPECT_EQ(Crc32(""), 0u);
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);  // the standard (zlib) check value
  std::string bytes;
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < 256; ++i) bytes.push_back(static_cast<char>(i));
  bytes += "abc";
  EXPECT_EQ(Crc32(bytes), 0x9D3A9924u);  // python3: zlib.crc32(bytes(range(256))*3+b'abc')
  // Fed in uneven pieces: the same value.
  for (const size_t split : {1u, 7u, 8u, 9u, 500u}) {
    const uint32_t first = Crc32Update(0, bytes.data(), split);
    EXPECT_EQ(Crc32Update(first, bytes.data() + split, bytes.size() - split), 0x9D3A9924u) << split;
  }
}

// b[i] = ((i * 2654435761) >> 13) & 0xFF; expected values from
// python3: zlib.crc32(b[:n]) (and b[3:100003] for an unaligned start).
TEST(McapCrc32, MatchesZlibOnEveryLengthClass) {
  std::string b(1 << 20, '\0');
  for (size_t i = 0; i < b.size(); ++i)
    b[i] = static_cast<char>(((uint64_t{i} * 2654435761u) >> 13) & 0xFF);
  const std::vector<std::pair<size_t, uint32_t>> expected = {
      {1, 0xd202ef8du},       {15, 0x0856e294u},   {16, 0x526fdea4u},   {17, 0xc13c1805u},
      {63, 0x07621d4du},      {64, 0x62d515b2u},   {65, 0xd3bb4b9eu},   {127, 0x2547062eu},
      {128, 0xd54a6c92u},     {255, 0x75c2d8c2u},  {256, 0xcdadae3bu},  {4099, 0xd8a2e7efu},
      {65543, 0xfb3d4c39u},   {1 << 20, 0x4091419du}};
  for (const auto& [n, crc] : expected) EXPECT_EQ(Crc32(std::string_view(b).substr(0, n)), crc) << n;
  EXPECT_EQ(Crc32(std::string_view(b).substr(3, 100000)), 0xd27851fbu);
  // A megabyte in pieces of odd sizes: the same as at once.
  uint32_t crc = 0;
  for (size_t at = 0, piece = 1; at < b.size(); at += piece, piece = piece * 3 + 1)
    crc = Crc32Update(crc, b.data() + at, std::min(piece, b.size() - at));
  EXPECT_EQ(crc, 0x4091419du);
}

// talker.mcap (written by the ROS 2 tools) stores the CRC 0x56f2eadc for the
// decompressed records of its zstd chunk. With that field overwritten the
// reader reports the CRC it computed itself: the writer's value.
TEST(McapCrc32, ComputesTheCrcTheRos2WriterStored) {
  std::string bytes =
      mcap_test::ReadFile(std::string(RVLIO_TEST_DATA) + "/ros2_bags/mcap_talker/talker.mcap");
  uint64_t chunk_at = 0;
  for (const auto& r : mcap_test::WalkRecords(bytes, bytes.size()))
    if (r.opcode == 0x06) chunk_at = r.offset;
  ASSERT_GT(chunk_at, 0u);
  const size_t crc_at = chunk_at + 9 + 24;  // after start, end, uncompressed_size
  ASSERT_EQ(mcap_test::Le(bytes, crc_at, 4), 0x56f2eadcu);
  for (int i = 0; i < 4; ++i) bytes[crc_at + i] = static_cast<char>(0x11);
  auto reader = mcap::Reader::OpenBuffer(bytes, "talker_crc.mcap");
  ASSERT_TRUE(reader.ok()) << reader.status().message();
  mcap::Message m;
  const StatusOr<bool> got = (*reader)->Next(&m);
  ASSERT_FALSE(got.ok());
  EXPECT_NE(got.status().message().find("chunk at offset " + std::to_string(chunk_at) +
                                        ": CRC mismatch (stored 0x11111111, computed 0x56f2eadc)"),
            std::string::npos)
      << got.status().message();
}

}  // namespace
}  // namespace rvlio
