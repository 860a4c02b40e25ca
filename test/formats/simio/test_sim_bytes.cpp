// A default `rvlio simulate` gives pinned bytes, so the flight seed, the
// reference survey and the deformation, left at their defaults, change
// nothing: the checksums below are those of the files written by
//   rvlio simulate --preset tunnel --seed 1 --duration 1.5 --set lidar.columns=256 --out DIR
// (FNV-1a 64 of NAME.bag and NAME_gt.tum; NAME.yaml is left out: its comment
// block lists every simulator key).
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/api.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

uint64_t Fnv1a64(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << path;
  uint64_t h = 0xcbf29ce484222325ull;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it) {
    h ^= static_cast<uint8_t>(*it);
    h *= 0x100000001b3ull;
  }
  return h;
}

TEST(SimulateBytes, DefaultOutputsAreThoseOfTheEarlierSimulator) {
  const fs::path dir =
      fs::temp_directory_path() / ("rvlio_sim_bytes_" + std::to_string(::getpid()));
  SimulateArgs args;
  args.preset = "tunnel";
  args.seed = 1;
  args.duration_s = 1.5;
  args.overrides = {"lidar.columns=256"};
  args.out_dir = dir.string();
  StatusOr<SimulateResult> r = SimulateRecording(args);
  ASSERT_TRUE(r.ok()) << r.status().message();
  EXPECT_TRUE(r->reference_map_path.empty());
  EXPECT_FALSE(fs::exists(dir / "reference_map.pcd"));
  EXPECT_EQ(Fnv1a64(r->bag_path), 0xd8c4a7d2c74c69bdull);
  EXPECT_EQ(Fnv1a64(r->gt_path), 0x1760df7db5acd3b5ull);
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace rvlio
