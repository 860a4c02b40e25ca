// Huge-page hints for large buffers (common/memory.h): the reservation and
// the contents are those of a plain reserve, and on Linux with transparent
// huge pages the kernel records the hint on the buffer's pages.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/common/memory.h"

namespace rvlio {
namespace {

// The VmFlags of the mapping of this process that holds address a
// (/proc/self/smaps), or "" when none is found.
std::string VmFlagsAt(const void* a) {
  std::ifstream smaps("/proc/self/smaps");
  const uintptr_t address = reinterpret_cast<uintptr_t>(a);
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    unsigned long long begin = 0, end = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> begin >> dash >> end && dash == '-' &&
        line.find(':') > line.find(' ')) {
      inside = address >= begin && address < end;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line.substr(8) + " ";
    }
  }
  return "";
}

TEST(HugePages, ReserveKeepsContentsAndCapacity) {
  std::vector<double> v = {1.0, 2.0, 3.0};
  ReserveWithHugePages(&v, 4u << 20);  // 32 MiB
  EXPECT_GE(v.capacity(), 4u << 20);
  EXPECT_EQ(v, (std::vector<double>{1.0, 2.0, 3.0}));
  v.resize(4u << 20, 7.0);
  EXPECT_EQ(v[3], 7.0);
  EXPECT_EQ(v.back(), 7.0);

  std::string small = "abc";
  ReserveWithHugePages(&small, 10);  // below kHugePageMinBytes: a plain reserve
  EXPECT_EQ(small, "abc");
  AdviseHugePages(nullptr, size_t{1} << 30);  // no-op
  AdviseHugePages(small.data(), 1);           // no-op
}

TEST(HugePages, TheKernelRecordsTheHintOnALargeBuffer) {
  if (!std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled"))
    GTEST_SKIP() << "no transparent huge pages on this system";
  std::ifstream mode_file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode((std::istreambuf_iterator<char>(mode_file)), std::istreambuf_iterator<char>());
  if (mode.find("[never]") != std::string::npos)
    GTEST_SKIP() << "transparent huge pages are switched off (never)";
  std::vector<float> buffer;
  ReserveWithHugePages(&buffer, size_t{16} << 20);  // 64 MiB
  // The 2 MiB-aligned interior carries the "hg" flag (MADV_HUGEPAGE).
  const uintptr_t middle = reinterpret_cast<uintptr_t>(buffer.data()) + (size_t{32} << 20);
  const std::string flags = VmFlagsAt(reinterpret_cast<const void*>(middle));
  ASSERT_FALSE(flags.empty()) << "no mapping holds the buffer in /proc/self/smaps";
  EXPECT_NE(flags.find(" hg "), std::string::npos) << flags;
}

}  // namespace
}  // namespace rvlio
