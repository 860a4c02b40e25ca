// Reading PCD and PLY clouds (formats/point_cloud_file.h): files written by PCL's
// own writers in every encoding read back to the same points and fields;
// hand-written files for the cases PCL does not write (big-endian PLY, an
// element before the vertices); and every refusal, one line naming the file.
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/outputs/map_fields.h"
#include "rvlio/outputs/run_outputs.h"

#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_dir.h"

// A map.pcd point with every attribute, as a PCL user would declare it.
struct RvlioMapPoint {
  PCL_ADD_POINT4D;
  float intensity;
  double time;
  uint16_t ring;
  uint32_t scan_index;
  float deviation_m;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
};
POINT_CLOUD_REGISTER_POINT_STRUCT(RvlioMapPoint,
                                  (float, x, x)(float, y, y)(float, z, z)(float, intensity, intensity)
                                  (double, time, time)(uint16_t, ring, ring)
                                  (uint32_t, scan_index, scan_index)(float, deviation_m, deviation_m))

namespace rvlio {
namespace {

namespace fs = std::filesystem;

std::string FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

class PointCloudFileTest : public MapioTestDir {
 protected:
  std::string Write(const std::string& name, const std::string& bytes) const {
    std::ofstream(Path(name), std::ios::binary) << bytes;
    return Path(name);
  }
  static pcl::PointCloud<pcl::PointXYZI> Cloud(int n) {
    pcl::PointCloud<pcl::PointXYZI> c;
    for (int i = 0; i < n; ++i) {
      pcl::PointXYZI p;
      p.x = 0.5f * i;
      p.y = -1.25f + 0.001f * i;
      p.z = 3.0f;
      p.intensity = static_cast<float>(i % 7);
      c.push_back(p);
    }
    return c;
  }
  static void ExpectSame(const PointCloudFile& f, const pcl::PointCloud<pcl::PointXYZI>& c) {
    ASSERT_EQ(f.points.size(), c.size());
    const PointCloudField* intensity = f.Field("intensity");
    ASSERT_NE(intensity, nullptr);
    // Binary encodings are exact; PCL's ASCII writers print 8 digits.
    for (size_t i = 0; i < c.size(); ++i) {
      EXPECT_NEAR(f.points[i].x(), c[i].x, 1e-6);
      EXPECT_NEAR(f.points[i].y(), c[i].y, 1e-6);
      EXPECT_NEAR(f.points[i].z(), c[i].z, 1e-6);
      EXPECT_EQ(intensity->values[i], c[i].intensity);
      if (f.format.find("ascii") == std::string::npos) {
        EXPECT_EQ(f.points[i].y(), c[i].y);
      }
    }
  }
};

TEST_F(PointCloudFileTest, ReadsPclPcdInEveryEncoding) {
  const pcl::PointCloud<pcl::PointXYZI> c = Cloud(1000);
  pcl::PCDWriter w;
  ASSERT_EQ(w.writeASCII(Path("a.pcd"), c), 0);
  ASSERT_EQ(w.writeBinary(Path("b.pcd"), c), 0);
  ASSERT_EQ(w.writeBinaryCompressed(Path("c.pcd"), c), 0);
  for (const char* name : {"a.pcd", "b.pcd", "c.pcd"}) {
    SCOPED_TRACE(name);
    StatusOr<PointCloudFile> f = ReadPointCloud(Path(name));
    ASSERT_TRUE(f.ok()) << f.status().message();
    ExpectSame(*f, c);
  }
  EXPECT_EQ(ReadPointCloud(Path("c.pcd"))->format, "pcd binary_compressed");
  StatusOr<PointCloudFile> xyz_only = ReadPointCloud(Path("b.pcd"), PointCloudReadOptions{false});
  ASSERT_TRUE(xyz_only.ok());
  EXPECT_TRUE(xyz_only->fields.empty());
}

// A map.pcd of `run --map` carries deviation_m, NaN where the reference has
// no surface: the map readers (ReadMapPcd: merge, eval, --map) take its
// points, and the field reads back with its NaNs.
TEST_F(PointCloudFileTest, MapWithADeviationFieldReadsAsPointsAndField) {
  const std::vector<Eigen::Vector3d> points = {{1, 2, 3}, {-4.5, 0.25, 7}, {0, 0, -1}};
  const std::vector<double> deviation_m = {0.012, std::numeric_limits<double>::quiet_NaN(), -0.03};
  ASSERT_TRUE(WriteMapPcd(Path("map.pcd"), points, &deviation_m).ok());
  StatusOr<std::vector<Eigen::Vector3d>> xyz = ReadMapPcd(Path("map.pcd"));
  ASSERT_TRUE(xyz.ok()) << xyz.status().message();
  ASSERT_EQ(xyz->size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) EXPECT_TRUE(xyz->at(i).isApprox(points[i], 1e-6));
  StatusOr<PointCloudFile> cloud = ReadPointCloud(Path("map.pcd"), PointCloudReadOptions());
  ASSERT_TRUE(cloud.ok()) << cloud.status().message();
  const PointCloudField* field = cloud->Field("deviation_m");
  ASSERT_NE(field, nullptr);
  EXPECT_FLOAT_EQ(field->values[0], 0.012f);
  EXPECT_TRUE(std::isnan(field->values[1]));
  EXPECT_FLOAT_EQ(field->values[2], -0.03f);
}

// rvlio writes map.pcd itself (atomically, without PCL): the file must be
// byte for byte what PCL's binary writer makes of the same cloud, and PCL's
// reader must take the map with its deviation_m field (what CloudCompare and
// the PCL viewers show as a scalar field).
TEST_F(PointCloudFileTest, MapPcdIsWhatPclWritesAndReads) {
  const std::vector<Eigen::Vector3d> points = {{1, 2, 3}, {-4.5, 0.25, 7}, {0, 0, -1}};
  ASSERT_TRUE(WriteMapPcd(Path("ours.pcd"), points).ok());
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (const Eigen::Vector3d& p : points)
    cloud.push_back(pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                  static_cast<float>(p.z())));
  ASSERT_EQ(pcl::PCDWriter().writeBinary(Path("pcl.pcd"), cloud), 0);
  EXPECT_EQ(FileBytes(Path("ours.pcd")), FileBytes(Path("pcl.pcd")));

  const std::vector<double> deviation_m = {0.012, std::numeric_limits<double>::quiet_NaN(), -0.03};
  ASSERT_TRUE(WriteMapPcd(Path("deviation.pcd"), points, &deviation_m).ok());
  pcl::PCLPointCloud2 blob;
  ASSERT_EQ(pcl::io::loadPCDFile(Path("deviation.pcd"), blob), 0);
  ASSERT_EQ(blob.width * blob.height, points.size());
  int field = -1;
  for (size_t i = 0; i < blob.fields.size(); ++i)
    if (blob.fields[i].name == "deviation_m") field = static_cast<int>(i);
  ASSERT_GE(field, 0);
  ASSERT_EQ(blob.fields[field].datatype, pcl::PCLPointField::FLOAT32);
  std::vector<float> read(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    std::memcpy(&read[i], &blob.data[i * blob.point_step + blob.fields[field].offset],
                sizeof(float));
  EXPECT_FLOAT_EQ(read[0], 0.012f);
  EXPECT_TRUE(std::isnan(read[1]));
  EXPECT_FLOAT_EQ(read[2], -0.03f);
  pcl::PointCloud<pcl::PointXYZ> xyz;
  ASSERT_EQ(pcl::io::loadPCDFile(Path("deviation.pcd"), xyz), 0);
  ASSERT_EQ(xyz.size(), points.size());
  EXPECT_FLOAT_EQ(xyz[1].x, -4.5f);
}

struct BlobField {
  const char* name;
  uint32_t offset;
  uint8_t type;
};

// An unorganized PCLPointCloud2 of n points of `point_step` bytes with these
// fields, its data zeroed (the test fills it).
pcl::PCLPointCloud2 Blob(const std::vector<BlobField>& fields, uint32_t point_step, size_t n) {
  pcl::PCLPointCloud2 blob;
  for (const BlobField& f : fields) {
    pcl::PCLPointField field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.type;
    field.count = 1;
    blob.fields.push_back(field);
  }
  blob.point_step = point_step;
  blob.width = static_cast<uint32_t>(n);
  blob.height = 1;
  blob.row_step = blob.point_step * blob.width;
  blob.data.resize(blob.row_step);
  return blob;
}

// `ours` is byte for byte what PCL's writer makes of `blob` (which pads its
// file with zeros to a page); returns our file's bytes.
std::string ExpectPclWritesTheSame(const std::string& ours, const pcl::PCLPointCloud2& blob,
                                   const std::string& pcl_path) {
  EXPECT_EQ(pcl::PCDWriter().writeBinary(pcl_path, blob), 0);
  const std::string ours_bytes = FileBytes(ours), pcl_bytes = FileBytes(pcl_path);
  EXPECT_GE(pcl_bytes.size(), ours_bytes.size());
  EXPECT_EQ(pcl_bytes.substr(0, ours_bytes.size()), ours_bytes);
  EXPECT_EQ(pcl_bytes.find_first_not_of('\0', std::min(ours_bytes.size(), pcl_bytes.size())),
            std::string::npos);
  return ours_bytes;
}

// A map in a national grid (UTM: easting 5e5 m, northing 5.4e6 m, where a
// float32 keeps only decimetres) is written with x y z as float64: the header
// and the bytes are PCL's for such a cloud, PCL reads the doubles back, and so
// does our reader, exactly. Below kFloat32MillimetreReach_m the map stays float32.
TEST_F(PointCloudFileTest, FarMapPcdIsFloat64AndWhatPclWrites) {
  const std::vector<Eigen::Vector3d> points = {{500000.0011, 5400000.0022, 312.0033},
                                               {500012.25, 5399990.5, 300.0},
                                               {499999.999, 5400000.001, -1.0}};
  const std::vector<double> deviation_m = {0.012, std::numeric_limits<double>::quiet_NaN(), -0.03};
  EXPECT_TRUE(MapNeedsFloat64(points));
  EXPECT_FALSE(MapNeedsFloat64({{8191.9, -8191.9, 0.0}}));
  EXPECT_TRUE(MapNeedsFloat64({{0.0, -8192.0, 0.0}}));
  ASSERT_TRUE(WriteMapPcd(Path("ours.pcd"), points, &deviation_m).ok());

  // The same cloud through PCL's writer.
  pcl::PCLPointCloud2 blob = Blob({{"x", 0, pcl::PCLPointField::FLOAT64},
                                   {"y", 8, pcl::PCLPointField::FLOAT64},
                                   {"z", 16, pcl::PCLPointField::FLOAT64},
                                   {"deviation_m", 24, pcl::PCLPointField::FLOAT32}},
                                  28, points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    std::memcpy(&blob.data[i * 28], points[i].data(), 24);
    const float d = static_cast<float>(deviation_m[i]);
    std::memcpy(&blob.data[i * 28 + 24], &d, 4);
  }
  const std::string ours_bytes = ExpectPclWritesTheSame(Path("ours.pcd"), blob, Path("pcl.pcd"));
  EXPECT_NE(ours_bytes.find("SIZE 8 8 8 4\nTYPE F F F F\n"), std::string::npos);

  pcl::PCLPointCloud2 read;
  ASSERT_EQ(pcl::io::loadPCDFile(Path("ours.pcd"), read), 0);
  ASSERT_EQ(read.width * read.height, points.size());
  ASSERT_EQ(read.fields[1].name, "y");
  ASSERT_EQ(read.fields[1].datatype, pcl::PCLPointField::FLOAT64);
  for (size_t i = 0; i < points.size(); ++i) {
    double y = 0.0;
    std::memcpy(&y, &read.data[i * read.point_step + read.fields[1].offset], sizeof(y));
    EXPECT_EQ(y, points[i].y());
  }
  StatusOr<PointCloudFile> ours = ReadPointCloud(Path("ours.pcd"));
  ASSERT_TRUE(ours.ok()) << ours.status().message();
  EXPECT_EQ(ours->points, points);
  ASSERT_NE(ours->Field("deviation_m"), nullptr);
  EXPECT_FLOAT_EQ(ours->Field("deviation_m")->values[2], -0.03f);

  // Near the origin map.pcd stays float32, byte for byte PCL's PointXYZ file.
  ASSERT_TRUE(WriteMapPcd(Path("near.pcd"), {{8191.5, 0.0, 0.0}}).ok());
  EXPECT_NE(FileBytes(Path("near.pcd")).find("SIZE 4 4 4\n"), std::string::npos);
}

TEST_F(PointCloudFileTest, MapPcdWithAttributesIsWhatPclWritesAndReads) {
  MapCloud map;
  map.has_intensity = map.has_time = map.has_ring = map.has_scan_index = true;
  std::vector<double> deviation_m;
  for (int i = 0; i < 50; ++i) {
    map.p.emplace_back(0.25 * i - 3.0, std::cos(0.1 * i), 1.5 + 0.01 * i);
    map.intensity.push_back(static_cast<float>(i % 17) * 3.5f);
    map.t_ns.push_back(1'700'000'000'123'456'789 + 9'876'543LL * i);
    map.ring.push_back(static_cast<uint16_t>(i % 128));
    map.scan_index.push_back(static_cast<uint32_t>(70000 + i / 3));
    deviation_m.push_back(i % 6 == 0 ? std::numeric_limits<double>::quiet_NaN() : 0.001 * i);
  }
  ASSERT_TRUE(WriteMapPcd(Path("ours.pcd"), map, &deviation_m).ok());

  // The same cloud through PCL's writer.
  pcl::PCLPointCloud2 blob = Blob(
      {{"x", 0, pcl::PCLPointField::FLOAT32},          {"y", 4, pcl::PCLPointField::FLOAT32},
       {"z", 8, pcl::PCLPointField::FLOAT32},          {"intensity", 12, pcl::PCLPointField::FLOAT32},
       {"time", 16, pcl::PCLPointField::FLOAT64},      {"ring", 24, pcl::PCLPointField::UINT16},
       {"scan_index", 26, pcl::PCLPointField::UINT32}, {"deviation_m", 30, pcl::PCLPointField::FLOAT32}},
      34, map.size());
  for (size_t i = 0; i < map.size(); ++i) {
    uint8_t* d = &blob.data[i * 34];
    const float xyz[3] = {static_cast<float>(map.p[i].x()), static_cast<float>(map.p[i].y()),
                          static_cast<float>(map.p[i].z())};
    const double t = MapTimeSeconds(map.t_ns[i]);
    const float dev = static_cast<float>(deviation_m[i]);
    std::memcpy(d, xyz, 12);
    std::memcpy(d + 12, &map.intensity[i], 4);
    std::memcpy(d + 16, &t, 8);
    std::memcpy(d + 24, &map.ring[i], 2);
    std::memcpy(d + 26, &map.scan_index[i], 4);
    std::memcpy(d + 30, &dev, 4);
  }
  const std::string ours_bytes = ExpectPclWritesTheSame(Path("ours.pcd"), blob, Path("pcl.pcd"));
  EXPECT_NE(ours_bytes.find("FIELDS x y z intensity time ring scan_index deviation_m\n"
                            "SIZE 4 4 4 4 8 2 4 4\nTYPE F F F F F U U F\n"),
            std::string::npos);

  // PCL's reader into a point type of these fields.
  pcl::PointCloud<RvlioMapPoint> read;
  ASSERT_EQ(pcl::io::loadPCDFile(Path("ours.pcd"), read), 0);
  ASSERT_EQ(read.size(), map.size());
  for (size_t i = 0; i < map.size(); ++i) {
    EXPECT_EQ(read[i].x, static_cast<float>(map.p[i].x()));
    EXPECT_EQ(read[i].z, static_cast<float>(map.p[i].z()));
    EXPECT_EQ(read[i].intensity, map.intensity[i]);
    EXPECT_EQ(read[i].time, MapTimeSeconds(map.t_ns[i]));
    EXPECT_EQ(read[i].ring, map.ring[i]);
    EXPECT_EQ(read[i].scan_index, map.scan_index[i]);
    if (std::isnan(deviation_m[i])) EXPECT_TRUE(std::isnan(read[i].deviation_m));
    else EXPECT_EQ(read[i].deviation_m, static_cast<float>(deviation_m[i]));
  }
  // And rvlio's own reader gives the map back, the time to what a double
  // of UNIX seconds holds (half of its 0.24 us step in 2023).
  StatusOr<MapCloudFile> back = ReadMapCloud(Path("ours.pcd"));
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_TRUE(back->has_deviation);
  EXPECT_EQ(back->map.intensity, map.intensity);
  EXPECT_EQ(back->map.ring, map.ring);
  EXPECT_EQ(back->map.scan_index, map.scan_index);
  ASSERT_EQ(back->map.t_ns.size(), map.size());
  for (size_t i = 0; i < map.size(); ++i) {
    EXPECT_LE(std::abs(back->map.t_ns[i] - map.t_ns[i]), 125) << i;
    EXPECT_EQ(back->map.p[i].y(), static_cast<double>(static_cast<float>(map.p[i].y())));
  }
}

TEST_F(PointCloudFileTest, ReadMapCloudRefusesFieldsNoMapHas) {
  const std::string header = "VERSION 0.7\nFIELDS x y z ring\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                             "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n";
  const struct { const char* name; std::string bytes; const char* says; } cases[] = {
      {"negative_ring.pcd", header + "1 2 3 4\n1 2 3 -1\n", "point 1: ring -1 is not a whole number"},
      {"fraction_ring.pcd", header + "1 2 3 4.5\n1 2 3 1\n", "point 0: ring 4.5"},
      {"twice.pcd",
       "VERSION 0.7\nFIELDS x y z ring ring\nSIZE 4 4 4 2 2\nTYPE F F F U U\nCOUNT 1 1 1 1 1\n"
       "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 4 5\n",
       "field ring appears twice"},
      {"float_time.pcd",
       "VERSION 0.7\nFIELDS x y z time\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
       "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 4\n",
       "field time is F4"},
  };
  for (const auto& c : cases) {
    StatusOr<MapCloudFile> r = ReadMapCloud(Write(c.name, c.bytes));
    ASSERT_FALSE(r.ok()) << c.name;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
    EXPECT_NE(r.status().message().find(Path(c.name)), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(c.says), std::string::npos) << r.status().message();
    EXPECT_EQ(r.status().message().find('\n'), std::string::npos);
  }
}

TEST_F(PointCloudFileTest, ReadsPclPlyAsciiAndBinary) {
  const pcl::PointCloud<pcl::PointXYZI> c = Cloud(500);
  pcl::PLYWriter w;
  ASSERT_EQ(w.write(Path("a.ply"), c, false), 0);
  ASSERT_EQ(w.write(Path("b.ply"), c, true), 0);
  for (const char* name : {"a.ply", "b.ply"}) {
    SCOPED_TRACE(name);
    StatusOr<PointCloudFile> f = ReadPointCloud(Path(name));
    ASSERT_TRUE(f.ok()) << f.status().message();
    ExpectSame(*f, c);
  }
}

// Big-endian doubles and a uchar, after an element of another kind.
TEST_F(PointCloudFileTest, ReadsBigEndianPlyAfterAnotherElement) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\ncomment test\nelement camera 1\nproperty float f\n"
      "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
      "property uchar red\nend_header\n";
  bytes.append(4, '\x7f');  // the camera record
  auto put_double = [&](double v) {
    char b[8];
    std::memcpy(b, &v, 8);
    for (int i = 7; i >= 0; --i) bytes.push_back(b[i]);
  };
  put_double(1.5), put_double(-2.0), put_double(1e-3), bytes.push_back('\xff');
  put_double(10.0), put_double(20.0), put_double(30.0), bytes.push_back('\x07');
  StatusOr<PointCloudFile> f = ReadPointCloud(Write("be.ply", bytes));
  ASSERT_TRUE(f.ok()) << f.status().message();
  ASSERT_EQ(f->points.size(), 2u);
  EXPECT_EQ(f->points[0], Eigen::Vector3d(1.5, -2.0, 1e-3));
  EXPECT_EQ(f->points[1], Eigen::Vector3d(10.0, 20.0, 30.0));
  EXPECT_EQ(f->Field("red")->values[0], 255.0f);
  EXPECT_EQ(f->Field("red")->values[1], 7.0f);
}

// The message of a refused file: one line that names it.
void ExpectRefused(const StatusOr<PointCloudFile>& f, const std::string& path,
                   const std::string& words) {
  ASSERT_FALSE(f.ok());
  const std::string& m = f.status().message();
  EXPECT_EQ(f.status().code(), StatusCode::kInvalidInput);
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_EQ(m.rfind(path, 0), 0u) << m;
  EXPECT_NE(m.find(words), std::string::npos) << m;
}

TEST_F(PointCloudFileTest, RefusesBadFilesWithOneLineNamingThem) {
  const pcl::PointCloud<pcl::PointXYZI> c = Cloud(100);
  pcl::PCDWriter w;
  ASSERT_EQ(w.writeBinary(Path("b.pcd"), c), 0);
  ASSERT_EQ(w.writeBinaryCompressed(Path("c.pcd"), c), 0);
  ASSERT_EQ(w.writeASCII(Path("a.pcd"), c), 0);
  auto truncate = [&](const std::string& name, size_t drop) {
    const size_t size = fs::file_size(Path(name));
    fs::resize_file(Path(name), size - drop);
    return Path(name);
  };
  ExpectRefused(ReadPointCloud(Path("missing.pcd")), Path("missing.pcd"), "cannot open");
  ExpectRefused(ReadPointCloud(dir_.string()), dir_.string(), "directory");
  ExpectRefused(ReadPointCloud(Write("e.pcd", "")), Path("e.pcd"), "empty file");
  ExpectRefused(ReadPointCloud(Write("t.txt", "hello\n")), Path("t.txt"), "not a PCD or PLY");
  ExpectRefused(ReadPointCloud(truncate("b.pcd", 10)), Path("b.pcd"), "truncated");
  ExpectRefused(ReadPointCloud(truncate("c.pcd", 10)), Path("c.pcd"), "truncated");
  ExpectRefused(ReadPointCloud(truncate("a.pcd", 40)), Path("a.pcd"), "truncated");
  ExpectRefused(ReadPointCloud(Write("z.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
                                              "WIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA ascii\n")),
                Path("z.pcd"), "empty point cloud");
  ExpectRefused(ReadPointCloud(Write("n.pcd", "FIELDS x y z\nPOINTS 3\nDATA ascii\n"
                                              "1 2 3\nnan 0 0\n0 inf 1\n")),
                Path("n.pcd"), "2 of 3 points have a non-finite coordinate");
  ExpectRefused(ReadPointCloud(Write("x.pcd", "FIELDS a b c\nPOINTS 1\nDATA ascii\n1 2 3\n")),
                Path("x.pcd"), "no x, y and z");
  ExpectRefused(ReadPointCloud(Write("w.pcd", "FIELDS x y z\nPOINTS 1\nDATA ascii\n1 two 3\n")),
                Path("w.pcd"), "not a number");
  ExpectRefused(ReadPointCloud(Write("h.ply", "ply\nformat ascii 1.0\nelement vertex 2\n"
                                              "property float x\nproperty float y\n"
                                              "property float z\nend_header\n0 0 0\n")),
                Path("h.ply"), "truncated");
  ExpectRefused(ReadPointCloud(Write("f.ply", "ply\nformat ascii 1.0\nelement face 2\n"
                                              "property list uchar int vertex_indices\nend_header\n")),
                Path("f.ply"), "no vertex element");
}

TEST_F(PointCloudFileTest, ReadingLeavesTheFileAndItsFolderUnchanged) {
  pcl::PCDWriter w;
  ASSERT_EQ(w.writeBinaryCompressed(Path("c.pcd"), Cloud(50)), 0);
  const auto before = fs::last_write_time(Path("c.pcd"));
  const auto size = fs::file_size(Path("c.pcd"));
  ASSERT_TRUE(ReadPointCloud(Path("c.pcd")).ok());
  EXPECT_EQ(fs::last_write_time(Path("c.pcd")), before);
  EXPECT_EQ(fs::file_size(Path("c.pcd")), size);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// MapPointsAsStored is what ReadMapPcd gives back of the written map.pcd,
// bit for bit, in both encodings (compare's map figures rest on it): random
// points of every magnitude below the float64 reach (float32, each of x y z
// rounded), and the same shifted to UTM coordinates (float64, unchanged).
TEST_F(PointCloudFileTest, MapPointsAsStoredIsWhatTheFileGivesBack) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> near;
  for (int i = 0; i < 1001; ++i) {  // an odd count: no vector lane left unchecked
    const double scale = std::pow(10.0, 3.0 * (u(rng) + 1.0) / 2.0 - 1.0);  // 0.1 .. 100 m
    near.emplace_back(scale * u(rng), scale * u(rng), scale * u(rng));
  }
  std::vector<Eigen::Vector3d> far = near;
  for (Eigen::Vector3d& p : far) p += Eigen::Vector3d(500000.0, 5400000.0, 250.0);
  for (const auto* points : {&near, &far}) {
    const std::vector<Eigen::Vector3d> stored = MapPointsAsStored(*points);
    ASSERT_TRUE(WriteMapPcd(Path("map.pcd"), *points).ok());
    StatusOr<std::vector<Eigen::Vector3d>> read = ReadMapPcd(Path("map.pcd"));
    ASSERT_TRUE(read.ok()) << read.status().message();
    ASSERT_EQ(read->size(), stored.size());
    int rounded = 0;
    for (size_t i = 0; i < stored.size(); ++i) {
      ASSERT_EQ(stored[i], (*read)[i]) << i;
      for (int k = 0; k < 3; ++k) rounded += stored[i][k] != (*points)[i][k] ? 1 : 0;
    }
    if (points == &near) EXPECT_GT(rounded, 2900);  // nearly every coordinate moves
    else EXPECT_EQ(rounded, 0);
  }
  EXPECT_TRUE(MapPointsAsStored({}).empty());
}

}  // namespace
}  // namespace rvlio
