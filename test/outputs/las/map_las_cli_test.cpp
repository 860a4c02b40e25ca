// output.las and survey.crs end to end on a 6 s simulated tunnel (the flight
// past a painted band that LasReaders reads too): `run`,
// `refine --chunk 1 --of 1` and `merge` write map.las beside map.pcd (the same
// points, the CRS's WKT) only when asked; an unknown survey.crs is exit 2
// before the recording is read, with nothing written.
#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "las_test_util.h"
#include "rvlio/formats/point_cloud_file.h"

namespace rvlio {
namespace {

using las_test::At;
using testing_cli::RunTool;
using testing_cli::ToolRun;

// map.las of `dir` holds the points of its map.pcd (float) to the millimetre.
void ExpectLasMatchesPcd(const std::string& dir, bool with_crs) {
  StatusOr<PointCloudFile> pcd = ReadPointCloud(dir + "/map.pcd", {true, true});
  ASSERT_TRUE(pcd.ok()) << pcd.status().message();
  const std::string b = las_test::ReadBytes(dir + "/map.las");
  ASSERT_GE(b.size(), 375u) << dir;
  ASSERT_EQ(At<uint64_t>(b, 247), pcd->points.size()) << dir;
  ASSERT_GT(pcd->points.size(), 100u);
  const uint32_t start = At<uint32_t>(b, 96);
  const uint16_t length = At<uint16_t>(b, 105);
  for (size_t i = 0; i < pcd->points.size(); ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_NEAR(At<int32_t>(b, start + length * i + 4 * k) * 0.001 + At<double>(b, 155 + 8 * k),
                  pcd->points[i][k], 0.0006) << dir << " point " << i;
  EXPECT_EQ(b.find("AUTHORITY[\"EPSG\",\"25832\"]") != std::string::npos, with_crs) << dir;
}

TEST(MapLasCli, RunRefineAndMergeWriteMapLasWhenAsked) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_map_las");
  ASSERT_FALSE(dir.empty());
  const ToolRun sim = las_test::SimulateBandFlight(dir + "/sim", dir);
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string input = "--bag " + dir + "/sim/tunnel.bag --config " + dir + "/sim/tunnel.yaml";
  const std::string las = " --set output.las=true --set survey.crs=EPSG:25832";

  ToolRun r = RunTool("run " + input + " --out " + dir + "/plain", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/plain/map.las")) << "written without output.las";

  r = RunTool("run " + input + " --out " + dir + "/run" + las, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectLasMatchesPcd(dir + "/run", true);

  r = RunTool("refine " + input + " --init " + dir + "/run/trajectory.tum --chunk 1 --of 1 --out " +
                  dir + "/chunk1 --set refine.rounds=1 --set output.las=true",
              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectLasMatchesPcd(dir + "/chunk1", false);

  r = RunTool("merge --chunks " + dir + "/chunk1 --out " + dir + "/merged", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectLasMatchesPcd(dir + "/merged", false);

  // An unknown CRS: exit 2 naming it, before the recording is read.
  r = RunTool("run " + input + " --out " + dir + "/bad --set survey.crs=EPSG:12345678", dir);
  testing_cli::ExpectOneErrorLine(r, "run", "survey.crs 'EPSG:12345678'");
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio
