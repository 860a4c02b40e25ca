// CRC-32 of src/io/mcap_records.h (slicing by 8) against known values.
#include <string>

#include <gtest/gtest.h>

#include "../../src/io/mcap_records.h"

namespace rvlio {
namespace {

using mcap::detail::Crc32;
using mcap::detail::Crc32Update;

TEST(McapCrc32, KnownValues) {
  EXPECT_EQ(Crc32(""), 0u);
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);  // the standard check value
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

}  // namespace
}  // namespace rvlio
