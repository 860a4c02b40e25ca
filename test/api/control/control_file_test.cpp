// The control file (formats/control_file.h) and NavSatFix messages
// (formats/navsatfix.h): what is read, and every refusal with its one line.
#include <gtest/gtest.h>

#include "rvlio/formats/control_file.h"
#include "rvlio/formats/navsatfix.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

StatusOr<std::vector<ControlRow>> Parse(const std::string& text) {
  return ParseControlFile(text, "marks.csv");
}

void ExpectRefused(const std::string& text, const std::string& part) {
  StatusOr<std::vector<ControlRow>> rows = Parse(text);
  ASSERT_FALSE(rows.ok()) << text;
  EXPECT_EQ(rows.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(rows.status().message().find(part), std::string::npos) << rows.status().message();
  EXPECT_EQ(rows.status().message().find('\n'), std::string::npos);
  EXPECT_EQ(rows.status().message().rfind("marks.csv", 0), 0u) << rows.status().message();
}

TEST(ControlFile, ReadsMarksTargetsRolesSigmasAndTimes) {
  StatusOr<std::vector<ControlRow>> rows = Parse(
      "# survey of 2026-01-12\n"
      "name, x, y, z, role, sigma_m, t_start, t_end, map_x, map_y, map_z\n"
      "M1,500000.1234,5400000.5678,250.001,,,,,,,\n"
      "M2,500050,5400000,250,check,0.01,1700000010.5,1700000014.25,,,\n"
      "\n"
      "T1,500010,5400004,252,control,,,,10.5,4.9,2.0\n");
  ASSERT_TRUE(rows.ok()) << rows.status().message();
  ASSERT_EQ(rows->size(), 3u);
  const ControlRow& m1 = (*rows)[0];
  EXPECT_EQ(m1.line, 3);
  EXPECT_EQ(m1.name, "M1");
  EXPECT_DOUBLE_EQ(m1.p_survey.x(), 500000.1234);
  EXPECT_DOUBLE_EQ(m1.p_survey.y(), 5400000.5678);
  EXPECT_EQ(m1.role, ControlRole::kControl);
  EXPECT_EQ(m1.sigma_m, 0.0);
  EXPECT_FALSE(m1.has_times);
  EXPECT_FALSE(m1.target);
  const ControlRow& m2 = (*rows)[1];
  EXPECT_EQ(m2.role, ControlRole::kCheck);
  EXPECT_DOUBLE_EQ(m2.sigma_m, 0.01);
  ASSERT_TRUE(m2.has_times);
  EXPECT_EQ(m2.t_start_ns, 1700000010500000000);
  EXPECT_EQ(m2.t_end_ns, 1700000014250000000);
  const ControlRow& t1 = (*rows)[2];
  EXPECT_EQ(t1.line, 6);
  ASSERT_TRUE(t1.target);
  EXPECT_TRUE(t1.p_map.isApprox(Eigen::Vector3d(10.5, 4.9, 2.0)));
}

TEST(ControlFile, ColumnsInAnyOrderAndOnlyTheRequiredOnes) {
  // Also: a spreadsheet's byte-order mark and Windows line ends.
  StatusOr<std::vector<ControlRow>> rows = Parse("\xEF\xBB\xBFz,name,y,x\r\n1,A,2,3\r\n4,B,5,6\r\n");
  ASSERT_TRUE(rows.ok()) << rows.status().message();
  EXPECT_TRUE((*rows)[1].p_survey.isApprox(Eigen::Vector3d(6, 5, 4)));
}

TEST(ControlFile, RefusesWhatItCannotRead) {
  ExpectRefused("", "no header line");
  ExpectRefused("name,x,y\nA,1,2\n", "lacks the column 'z'");
  ExpectRefused("name,x,y,z,sigma\nA,1,2,3,0.1\n", "unknown column 'sigma'");
  ExpectRefused("name,x,y,z,x\nA,1,2,3,4\n", "column 'x' appears twice");
  ExpectRefused("name,x,y,z\n", "no control point");
  ExpectRefused("name,x,y,z\nA,1,2\n", "line 2: 3 cells, the header has 4");
  ExpectRefused("name,x,y,z\nA,1,2,3\nB,1,2,abc\n", "line 3: z 'abc' is not a number");
  ExpectRefused("name,x,y,z\nA,1,2,nan\n", "z 'nan' is not a number");
  ExpectRefused("name,x,y,z\n,1,2,3\n", "the name is empty");
  ExpectRefused("name,x,y,z\nA,1,2,3\nA,4,5,6\n", "the name 'A' appears twice");
  ExpectRefused("name,x,y,z,role\nA,1,2,3,chek\n", "role 'chek'");
  ExpectRefused("name,x,y,z,sigma_m\nA,1,2,3,-0.01\n", "sigma_m must be positive");
  ExpectRefused("name,x,y,z,t_start,t_end\nA,1,2,3,10,\n", "t_start and t_end go together");
  ExpectRefused("name,x,y,z,t_start,t_end\nA,1,2,3,10,9\n", "t_end must be after t_start");
  ExpectRefused("name,x,y,z,map_x,map_y,map_z\nA,1,2,3,1,2,\n", "go together");
  ExpectRefused("name,x,y,z,t_start,t_end,map_x,map_y,map_z\nA,1,2,3,1,2,1,2,3\n", "not both");
  EXPECT_FALSE(ReadControlFile("/nonexistent/marks.csv").ok());
  StatusOr<std::vector<ControlRow>> folder = ReadControlFile("/tmp");
  ASSERT_FALSE(folder.ok());
  EXPECT_NE(folder.status().message().find("is a folder"), std::string::npos);
  // Binary bytes as a header: one short printable line.
  std::string garbage(3000, '\x01');
  garbage[7] = '\n';
  StatusOr<std::vector<ControlRow>> bad = Parse(garbage);
  ASSERT_FALSE(bad.ok());
  EXPECT_LT(bad.status().message().size(), 250u);
  EXPECT_NE(bad.status().message().find("unknown column '\?\?\?\?\?\?\?'"), std::string::npos)
      << bad.status().message();
}

TEST(NavSatFix, CdrRoundTrip) {
  NavSatFix f;
  f.header_stamp_ns = 1700000012345678901;
  f.frame_id = "gnss";
  f.status = 2;
  f.latitude_deg = 48.7412345678;
  f.longitude_deg = 9.1012345678;
  f.altitude_m = 312.25;
  f.position_covariance = {1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 9e-4};
  f.covariance_type = 2;
  const std::vector<uint8_t> bytes = EncodeNavSatFixCdr(f);
  StatusOr<NavSatFix> back = DecodeNavSatFixCdr(bytes.data(), bytes.size(), "fix");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ(back->header_stamp_ns, f.header_stamp_ns);
  EXPECT_EQ(back->status, 2);
  EXPECT_EQ(back->latitude_deg, f.latitude_deg);
  EXPECT_EQ(back->longitude_deg, f.longitude_deg);
  EXPECT_EQ(back->altitude_m, f.altitude_m);
  EXPECT_EQ(back->position_covariance, f.position_covariance);
  EXPECT_EQ(back->covariance_type, 2);
  // Cut short: refused, not read past the end.
  EXPECT_FALSE(DecodeNavSatFixCdr(bytes.data(), bytes.size() - 3, "fix").ok());
  EXPECT_FALSE(ParseRos1NavSatFix(bytes.data(), 10, "fix").ok());
}

// NavSatFix messages written into a ROS1 bag and a ROS 2 MCAP and read back:
// fixes without a solution are skipped and counted, a latitude out of range
// is refused naming the message.
TEST(NavSatFix, ReadFromRos1AndRos2RecordingsWithNoFixCountedAndBadLatitudeRefused) {
  const std::string dir = ::testing::TempDir();
  for (const std::string format : {"ros1", "mcap"}) {
    SCOPED_TRACE(format);
    const std::string path = dir + "/fixes_" + format + (format == "ros1" ? ".bag" : ".mcap");
    for (const bool bad : {false, true}) {
      BagWriterOptions options;
      options.format = format;
      StatusOr<std::unique_ptr<SensorBagWriter>> w = SensorBagWriter::Create(path, options);
      ASSERT_TRUE(w.ok()) << w.status().message();
      for (int k = 0; k < 4; ++k) {
        NavSatFix f;
        f.header_stamp_ns = 1700000000000000000 + k * 200000000LL;
        f.latitude_deg = 48.7 + 1e-6 * k;
        f.longitude_deg = 9.1;
        f.altitude_m = 300.0;
        if (k == 1) f.status = kNavSatStatusNoFix;
        if (bad && k == 2) f.latitude_deg = 95.0;
        ASSERT_TRUE((*w)->WriteNavSatFix("/gnss/fix", f).ok());
      }
      ASSERT_TRUE((*w)->Close().ok());
      NavSatFixStats stats;
      StatusOr<std::vector<NavSatFix>> read = ReadNavSatFixes(path, "/gnss/fix", &stats);
      if (!bad) {
        ASSERT_TRUE(read.ok()) << read.status().message();
        EXPECT_EQ(read->size(), 3u);
        EXPECT_EQ(stats.messages, 4);
        EXPECT_EQ(stats.no_fix, 1);
        EXPECT_EQ((*read)[1].latitude_deg, 48.7 + 2e-6);
        continue;
      }
      ASSERT_FALSE(read.ok());
      EXPECT_NE(read.status().message().find("gnss.topic '/gnss/fix' in '" + path +
                                             "': message 2"),
                std::string::npos)
          << read.status().message();
      EXPECT_NE(read.status().message().find("latitude 95"), std::string::npos);
    }
    NavSatFixStats stats;
    EXPECT_FALSE(ReadNavSatFixes(path, "/other", &stats).ok());
  }
}

}  // namespace
}  // namespace rvlio
