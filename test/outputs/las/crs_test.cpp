// formats/crs.h: survey.crs strings resolved by PROJ into the OGC WKT of
// map.las, one-line errors for what is not a usable CRS, and latitude /
// longitude into a projected CRS (the easting and northing on the central
// meridian against the meridian arc integrated here).
#include <gtest/gtest.h>

#include "rvlio/formats/crs.h"

namespace rvlio {
namespace {

TEST(Crs, EpsgCodeBecomesWkt1WithItsAuthority) {
  StatusOr<Crs> crs = ResolveCrs("EPSG:25832");
  ASSERT_TRUE(crs.ok()) << crs.status().message();
  EXPECT_EQ(crs->name, "ETRS89 / UTM zone 32N");
  EXPECT_EQ(crs->wkt.rfind("PROJCS[\"ETRS89 / UTM zone 32N\"", 0), 0u) << crs->wkt;
  EXPECT_NE(crs->wkt.find("AUTHORITY[\"EPSG\",\"25832\"]"), std::string::npos) << crs->wkt;
  EXPECT_EQ(crs->wkt.find('\n'), std::string::npos) << "one line";
}

TEST(Crs, ProjStringsWktAndCompoundCrsAreAccepted) {
  StatusOr<Crs> proj = ResolveCrs("+proj=utm +zone=33 +ellps=GRS80 +units=m +type=crs");
  ASSERT_TRUE(proj.ok()) << proj.status().message();
  EXPECT_EQ(proj->wkt.rfind("PROJCS[", 0), 0u) << proj->wkt;
  StatusOr<Crs> epsg = ResolveCrs("EPSG:25832");
  ASSERT_TRUE(epsg.ok());
  StatusOr<Crs> again = ResolveCrs(epsg->wkt);  // WKT in, the same CRS out
  ASSERT_TRUE(again.ok()) << again.status().message();
  EXPECT_EQ(again->name, epsg->name);
  StatusOr<Crs> compound = ResolveCrs("EPSG:25832+7837");  // + DHHN2016 height
  ASSERT_TRUE(compound.ok()) << compound.status().message();
  EXPECT_EQ(compound->wkt.rfind("COMPD_CS[", 0), 0u) << compound->wkt;
}

TEST(Crs, UnknownGeographicAndNonCrsStringsAreOneLineNamingThem) {
  const struct { const char* crs; const char* says; } kBad[] = {
      {"EPSG:99999999", "unknown coordinate reference system"},
      {"not a crs", "unknown coordinate reference system"},
      {"EPSG:4326", "geographic"},
      {"EPSG:5783", "vertical"},
      {"+proj=utm +zone=32", "not a coordinate reference system"},
  };
  for (const auto& bad : kBad) {
    StatusOr<Crs> crs = ResolveCrs(bad.crs);
    ASSERT_FALSE(crs.ok()) << bad.crs;
    EXPECT_EQ(crs.status().code(), StatusCode::kInvalidInput);
    const std::string& m = crs.status().message();
    EXPECT_NE(m.find(std::string("survey.crs '") + bad.crs + "'"), std::string::npos) << m;
    EXPECT_NE(m.find(bad.says), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  EXPECT_TRUE(IsLocalCrs("local"));
  EXPECT_FALSE(IsLocalCrs("EPSG:25832"));
}

TEST(Crs, LatitudeLongitudeOnTheCentralMeridianGiveTheMeridianArc) {
  StatusOr<GeodeticToCrs> t = GeodeticToCrs::Create("EPSG:32632");  // WGS 84 / UTM 32N
  ASSERT_TRUE(t.ok()) << t.status().message();
  StatusOr<Eigen::Vector3d> p = t->Transform(48.0, 9.0, 250.0);
  ASSERT_TRUE(p.ok()) << p.status().message();
  EXPECT_NEAR(p->x(), 500000.0, 1e-6);
  // 0.9996 x the WGS 84 meridian arc to 48 deg (Simpson's rule, 200000 steps).
  EXPECT_NEAR(p->y(), 5316300.2245, 1e-3);
  EXPECT_NEAR(p->z(), 250.0, 1e-9) << "a 2D target keeps the ellipsoidal height";
  // One degree east: easting grows, northing hardly.
  StatusOr<Eigen::Vector3d> east = t->Transform(48.0, 10.0, 0.0);
  ASSERT_TRUE(east.ok());
  EXPECT_NEAR(east->x() - 500000.0, 74597.0, 10.0);  // k0 N cos(lat) x 1 deg = 74595.5 m, + higher order
  StatusOr<GeodeticToCrs> bad = GeodeticToCrs::Create("EPSG:4326");
  EXPECT_FALSE(bad.ok());
  StatusOr<Eigen::Vector3d> nan = t->Transform(std::nan(""), 9.0, 0.0);
  EXPECT_FALSE(nan.ok());
}

}  // namespace
}  // namespace rvlio
