// The per-scan column table (outputs/scan_columns.h): scans.csv and the
// Python per-scan table are generated from it.
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/outputs/scan_columns.h"

namespace rvlio {
namespace {

std::vector<std::string> Names(const std::vector<const ScanColumn*>& columns) {
  std::vector<std::string> names;
  for (const ScanColumn* c : columns) names.push_back(c->name);
  return names;
}

const ScanColumn& Column(const std::string& name) {
  for (const ScanColumn& c : AllScanColumns())
    if (name == c.name) return c;
  ADD_FAILURE() << "no column " << name;
  return AllScanColumns().front();
}

std::string Cell(const std::string& name, const ScanResult& scan, double rss_mb = 0.0) {
  return FormatScanCell(Column(name), ScanRecord{scan, rss_mb});
}

TEST(ScanColumnsTest, ColumnsEveryRunHasKeepTheirCsvOrderWithTheVelocityAfterThem) {
  // The order readers of scans.csv by position rely on; vx vy vz come after
  // the columns scans.csv always had.
  const std::vector<std::string> expected = {"t",
                                             "status",
                                             "raw_points",
                                             "points",
                                             "constraints",
                                             "iterations",
                                             "rv_active",
                                             "n_alpha_x",
                                             "n_alpha_y",
                                             "n_alpha_z",
                                             "scv",
                                             "coplanar",
                                             "repaired",
                                             "K",
                                             "rv_iterations",
                                             "coplanar_fraction",
                                             "localizability",
                                             "ms",
                                             "x",
                                             "y",
                                             "z",
                                             "acc_x",
                                             "acc_y",
                                             "acc_z",
                                             "rss_mb",
                                             "reinforced",
                                             "nis",
                                             "residual_median_m",
                                             "residual_rms_m",
                                             "diverged",
                                             "degeneracy_method",
                                             "degenerate",
                                             "weak_dirs",
                                             "weak_dir_x",
                                             "weak_dir_y",
                                             "weak_dir_z",
                                             "condition_number",
                                             "vx",
                                             "vy",
                                             "vz"};
  EXPECT_EQ(Names(ScanColumnsOf({})), expected);
  EXPECT_EQ(Names(ScanColumnsOf({ScanResult()})), expected);
}

TEST(ScanColumnsTest, NamesAreUniqueAndEveryColumnCanBeComputed) {
  std::set<std::string> names;
  for (const ScanColumn& c : AllScanColumns()) {
    EXPECT_TRUE(names.insert(c.name).second) << c.name;
    EXPECT_NE(c.unit, nullptr) << c.name;
    if (c.type == ScanValueType::kText)
      EXPECT_NE(c.text, nullptr) << c.name;
    else
      EXPECT_NE(c.value, nullptr) << c.name;
  }
}

TEST(ScanColumnsTest, OptionalGroupsAppearWhenSomeScanCarriesThemInTableOrder) {
  // Built in place: copying a ScanResult with an empty optional pose out of
  // an initializer list trips GCC 12's -Wmaybe-uninitialized (a false positive).
  std::vector<ScanResult> scans(2);
  const ScanResult& plain = scans[0];
  ScanResult& estimated = scans[1];
  estimated.T_imu_lidar = Pose3();
  estimated.time_offset_s = 0.01;
  estimated.map_overlap = 0.5;
  const std::vector<std::string> names = Names(ScanColumnsOf(scans));
  ASSERT_EQ(names.size(), AllScanColumns().size());
  for (size_t i = 0; i < names.size(); ++i) EXPECT_EQ(names[i], AllScanColumns()[i].name);
  // A scan without the estimate has empty cells there.
  EXPECT_EQ(Cell("ext_roll_deg", plain), "");
  EXPECT_EQ(Cell("ext_x_m", estimated), "0");
  EXPECT_EQ(Cell("time_offset_s", plain), "");
  EXPECT_EQ(Cell("time_offset_s", estimated), "0.01");
  EXPECT_EQ(Cell("map_overlap", plain), "");
  EXPECT_EQ(Cell("localized", plain), "0");
  std::vector<ScanResult> only_time(1);
  only_time[0].time_offset_s = 0.0;
  const std::vector<std::string> with_time = Names(ScanColumnsOf(only_time));
  EXPECT_EQ(with_time.back(), "time_offset_std_s");
  EXPECT_EQ(with_time.size(), ScanColumnsOf({}).size() + 2);
}

TEST(ScanColumnsTest, CellsAreWrittenInTheirColumnsFormat) {
  ScanResult r;
  r.t_ns = 1'500'000'001;
  r.raw_points = 1234567;
  r.rv.active = true;
  r.T_world_imu.t = Eigen::Vector3d(1.0 / 3.0, -2.5, 0.0);
  r.v_world_imu = Eigen::Vector3d(0.5, 0.0, -1.0);
  r.health.nis_per_dof = 1.0 / 3.0;  // residuals stay unknown (NaN)
  r.health.divergence_mask = (1u << static_cast<int>(DivergenceKind::kSpeed)) |
                             (1u << static_cast<int>(DivergenceKind::kNis));
  r.degeneracy.condition_number = std::numeric_limits<double>::infinity();
  EXPECT_EQ(Cell("t", r), "1.500000001");
  EXPECT_EQ(Cell("status", r), "updated");
  EXPECT_EQ(Cell("raw_points", r), "1234567");
  EXPECT_EQ(Cell("rv_active", r), "1");
  EXPECT_EQ(Cell("x", r), "0.333333333");  // nine significant digits
  EXPECT_EQ(Cell("vz", r), "-1");
  EXPECT_EQ(Cell("nis", r), "0.333333");  // statistics: six, empty when unknown
  EXPECT_EQ(Cell("residual_median_m", r), "");
  EXPECT_EQ(Cell("rss_mb", r, 12.25), "12.25");
  EXPECT_EQ(Cell("rss_mb", r, std::nan("")), "nan");  // not measured
  EXPECT_EQ(Cell("diverged", r), DivergenceKindNames(r.health.divergence_mask));
  EXPECT_EQ(Column("diverged").value(ScanRecord{r, 0.0}), 1.0);  // numeric readers: a flag
  EXPECT_EQ(Cell("weak_dir_x", r), "");                          // no weak direction
  EXPECT_EQ(Cell("condition_number", r), "inf");
  // Positions in a national grid keep six decimals (a UTM northing, easting).
  r.T_world_imu.t = Eigen::Vector3d(500000.0037144, 5400000.0005768, 312.25);
  EXPECT_EQ(Cell("x", r), "500000.003714");
  EXPECT_EQ(Cell("y", r), "5400000.000577");
  EXPECT_EQ(Cell("z", r), "312.25");
}

}  // namespace
}  // namespace rvlio
