// Determinism: the same bag and configuration give a byte-identical
// trajectory.tum (and map.pcd) across runs, whatever the working folder,
// thread-count variables or output path; for the IESKF, the smoother and
// refine. (test/cli checks two plain repeated runs of run; this adds the
// environment, the map and refine.)
#include <filesystem>

#include <gtest/gtest.h>

#include "badinput_util.h"

namespace rvlio::badinput {
namespace {

namespace fs = std::filesystem;

class DeterminismTest : public SimulatedSuite {
 protected:
  // Runs `run` once plainly and once from another folder, with relative
  // paths and thread-count variables set; returns both output folders.
  static std::pair<std::string, std::string> RunTwice(const std::string& name,
                                                      const std::string& extra) {
    const std::string a = dir_ + "/" + name + "_a";
    const ToolRun ra = Run(Bag(), a, extra);
    EXPECT_EQ(ra.exit_code, 0) << ra.err;
    const std::string elsewhere = dir_ + "/" + name + "_cwd";
    fs::create_directories(elsewhere);
    const ToolRun rb = RunToolWith("run --bag ../data/tunnel.bag --config ../data/tunnel.yaml"
                                   " --out ../" + name + "_b " + extra,
                                   dir_, elsewhere, "OMP_NUM_THREADS=2 OPENBLAS_NUM_THREADS=2");
    EXPECT_EQ(rb.exit_code, 0) << rb.err;
    return {a, dir_ + "/" + name + "_b"};
  }
  static void ExpectSameBytes(const std::string& a, const std::string& b, const char* file) {
    const std::string x = ReadFile(a + "/" + file), y = ReadFile(b + "/" + file);
    EXPECT_GT(x.size(), 100u) << file;
    EXPECT_TRUE(x == y) << file << " differs between " << a << " and " << b;
  }
};

TEST_F(DeterminismTest, IeskfIsByteIdenticalAcrossFoldersAndThreadVariables) {
  const auto [a, b] = RunTwice("ieskf", "--set backend=ieskf");
  ExpectSameBytes(a, b, "trajectory.tum");
  ExpectSameBytes(a, b, "map.pcd");
  ExpectSameBytes(a, dir_ + "/clean", "trajectory.tum");  // the suite's run, default backend
}

TEST_F(DeterminismTest, SmootherIsByteIdenticalAcrossFoldersAndThreadVariables) {
  const auto [a, b] = RunTwice("smoother", "--set backend=smoother");
  ExpectSameBytes(a, b, "trajectory.tum");
  ExpectSameBytes(a, b, "map.pcd");
}

TEST_F(DeterminismTest, RefineIsByteIdentical) {
  std::string outs[2];
  for (int i = 0; i < 2; ++i) {
    outs[i] = dir_ + "/refine_" + std::to_string(i);
    const ToolRun r = RunToolWith("refine --bag " + Bag() + " --config " + Sensors() + " --init " +
                                      Clean("trajectory.tum") + " --set refine.rounds=2 --out " +
                                      outs[i],
                                  dir_, i == 0 ? "" : dir_, i == 0 ? "" : "OMP_NUM_THREADS=2");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  ExpectSameBytes(outs[0], outs[1], "trajectory.tum");
  ExpectSameBytes(outs[0], outs[1], "map.pcd");
  // Refine changed the trajectory it started from (so the check is not vacuous).
  EXPECT_NE(ReadFile(outs[0] + "/trajectory.tum"), ReadFile(Clean("trajectory.tum")));
}

}  // namespace
}  // namespace rvlio::badinput
