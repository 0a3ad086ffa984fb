// Scan readers (PCD, PLY, XYZ, PTX) and poses.
#include <gtest/gtest.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "semioctree/scan_io.h"
#include "support/sample_trees.h"
#include "support/scratch.h"

namespace semioctree {
namespace {

TEST(ScanIo, ReadsPcdAndPlyDroppingInvalidPoints) {
  const auto dir = testing::temp_dir("scanio");
  Cloud c;
  c.push_back(pcl::PointXYZ{1.f, 2.f, 3.f});
  c.push_back(pcl::PointXYZ{std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f});
  c.push_back(pcl::PointXYZ{4.f, std::numeric_limits<float>::infinity(), 0.f});
  c.push_back(pcl::PointXYZ{-1.f, -2.f, -3.f});
  c.is_dense = false;
  pcl::io::savePCDFileBinary((dir / "a.pcd").string(), c);
  pcl::io::savePLYFileBinary((dir / "a.ply").string(), c);
  for (const char* name : {"a.pcd", "a.ply"}) {
    const auto scans = read_scans((dir / name).string());
    ASSERT_EQ(scans.size(), 1u) << name;
    EXPECT_EQ(scans[0].points->size(), 2u) << name;
    EXPECT_EQ(scans[0].invalid_dropped, 2u) << name;
    EXPECT_FLOAT_EQ((*scans[0].points)[1].z, -3.f);
  }
}

TEST(ScanIo, PcdViewpointIsTheScanPose) {
  const auto dir = testing::temp_dir("scanio-vp");
  Cloud c;
  c.push_back(pcl::PointXYZ{1.f, 0.f, 0.f});
  const Eigen::Vector4f origin(2.f, -3.f, 1.5f, 0.f);
  const Eigen::Quaternionf q(Eigen::AngleAxisf(float(30 * M_PI / 180), Eigen::Vector3f::UnitZ()));
  pcl::io::savePCDFileBinary((dir / "plain.pcd").string(), c);
  c.sensor_origin_ = origin;  // PCD VIEWPOINT
  c.sensor_orientation_ = q;
  pcl::io::savePCDFileBinary((dir / "posed.pcd").string(), c);
  const Scan posed = read_scans((dir / "posed.pcd").string()).at(0);
  EXPECT_TRUE(posed.pose_from_file);
  EXPECT_NEAR(posed.pose.position().x(), 2.0, 1e-6);
  EXPECT_NEAR(posed.pose.position().y(), -3.0, 1e-6);
  EXPECT_NEAR(posed.pose.position().z(), 1.5, 1e-6);
  EXPECT_NEAR(posed.pose.yaw_deg(), 30.0, 1e-4);
  // The point (1, 0, 0) of the scanner's frame, in the survey frame.
  const Cloud::Ptr world = to_survey_frame(posed);
  EXPECT_NEAR((*world)[0].x, 2.0 + std::cos(M_PI / 6), 1e-5);
  EXPECT_NEAR((*world)[0].y, -3.0 + std::sin(M_PI / 6), 1e-5);
  const Scan plain = read_scans((dir / "plain.pcd").string()).at(0);
  EXPECT_FALSE(plain.pose_from_file);
  EXPECT_TRUE(plain.pose.scanner_to_survey.isApprox(Eigen::Isometry3d::Identity()));
  std::filesystem::remove_all(dir);
}

TEST(ScanIo, ReadsXyzTextWithCommentsAndCommas) {
  const auto dir = testing::temp_dir("xyz");
  std::ofstream(dir / "a.xyz") << "# x y z\n1 2 3\n4,5,6, 0.5\n\n7\t8\t9 10 11 12\nnan 1 1\n";
  const auto scans = read_scans((dir / "a.xyz").string());
  ASSERT_EQ(scans[0].points->size(), 3u);
  EXPECT_EQ(scans[0].invalid_dropped, 1u);
  EXPECT_FLOAT_EQ((*scans[0].points)[1].y, 5.f);
  std::ofstream(dir / "bad.xyz") << "1 2 3\n1 2 oops\n";
  try {
    read_scans((dir / "bad.xyz").string());
    FAIL();
  } catch (const ScanReadError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.xyz:2:"), std::string::npos) << e.what();
  }
}

TEST(ScanIo, ReadsPtxScansWithTheirPoses) {
  const auto dir = testing::temp_dir("ptx");
  std::ofstream f(dir / "two.ptx");
  // Scan 1: 2 × 1 points, identity; scan 2: 1 × 2, rotated 90° about z, at (10, 0, 1).
  f << "2\n1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
    << "1 0 0 0.5\n0 0 0 0.5\n";
  f << "1\n2\n10 0 1\n0 1 0\n-1 0 0\n0 0 1\n0 1 0 0\n-1 0 0 0\n0 0 1 0\n10 0 1 1\n"
    << "1 0 0 0.5 10 20 30\n0 2 0 0.5 10 20 30\n";
  f.close();
  const auto scans = read_scans((dir / "two.ptx").string());
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[0].points->size(), 1u);
  EXPECT_EQ(scans[0].invalid_dropped, 1u);  // (0, 0, 0) is "no return"
  EXPECT_EQ(scans[1].points->size(), 2u);
  EXPECT_NEAR(scans[1].pose.position().x(), 10.0, 1e-12);
  EXPECT_NEAR(scans[1].pose.yaw_deg(), 90.0, 1e-9);
  const auto world = to_survey_frame(scans[1]);
  EXPECT_NEAR((*world)[0].x, 10.0, 1e-5);  // (1,0,0) rotated to (0,1,0), plus (10,0,1)
  EXPECT_NEAR((*world)[0].y, 1.0, 1e-5);
  EXPECT_NEAR((*world)[0].z, 1.0, 1e-5);
  std::ofstream(dir / "short.ptx") << "2\n1\n0 0 0\n";
  try {
    read_scans((dir / "short.ptx").string());
    FAIL();
  } catch (const ScanReadError& e) {
    EXPECT_NE(std::string(e.what()).find("short.ptx:4"), std::string::npos) << e.what();
  }
}

// A PTX header claiming more points than the rest of the file can hold is refused
// before the scan is allocated (found by fuzzing: 2.4 GB reserved for an 8-digit
// column count in a 400-byte file); an exact fit is read.
TEST(ScanIo, PtxScanSizeBeyondTheFileIsRefusedBeforeAllocating) {
  const auto dir = testing::temp_dir("ptx_size");
  const std::string header = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
  std::ofstream(dir / "huge.ptx") << "49999999\n3\n" << header << "1 0 0\n2 0 0\n";
  try {
    read_scans((dir / "huge.ptx").string());
    FAIL() << "read a scan of 149999997 points from a small file";
  } catch (const ScanReadError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("huge.ptx:1: scan 0 of 49999999 x 3 points needs at least"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("truncated, or its size is wrong"), std::string::npos) << what;
  }
  // Two points of the shortest form, the last without its line end: 11 bytes, enough.
  std::ofstream(dir / "tight.ptx") << "2\n1\n" << header << "1 0 0\n2 0 0";
  EXPECT_EQ(read_scans((dir / "tight.ptx").string())[0].points->size(), 2u);
}

// PCL's PLY reader asserts that an obj_info line starts with the word: a leading
// blank aborted the program (found by fuzzing). It is a clear error now, and
// obj_info without one still reads.
TEST(ScanIo, PlyObjInfoLineWithALeadingBlankIsAnError) {
  const auto dir = testing::temp_dir("ply_obj_info");
  for (const std::string lead : {" ", "\t", ""}) {
    const auto path = dir / "lead.ply";
    {
      std::ofstream f(path, std::ios::binary);
      f << "ply\nformat ascii 1.0\n"
        << lead << "obj_info num_rows 1\nelement vertex 2\n"
        << "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5 6\n";
    }
    if (lead.empty()) {
      EXPECT_EQ(read_scans(path.string())[0].points->size(), 2u);
      continue;
    }
    try {
      read_scans(path.string());
      FAIL() << "read a PLY whose obj_info line starts with a blank";
    } catch (const ScanReadError& e) {
      EXPECT_NE(std::string(e.what()).find(
                    "lead.ply: PLY header line 3: obj_info line starts with a blank"),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(ScanIo, PosesAndErrors) {
  const ScanPose p = parse_pose("1.5,-2,0.3,90");
  EXPECT_NEAR(p.position().y(), -2.0, 1e-12);
  EXPECT_NEAR(p.yaw_deg(), 90.0, 1e-9);
  EXPECT_NEAR(parse_pose("1 2 3").yaw_deg(), 0.0, 1e-12);
  EXPECT_THROW(parse_pose("1,2"), std::invalid_argument);
  EXPECT_THROW(parse_pose("a,b,c"), std::invalid_argument);
  const auto dir = testing::temp_dir("pose");
  std::ofstream(dir / "p.json") << R"({"x": 1, "y": 2, "z": 0.5, "yaw_deg": -30})";
  EXPECT_NEAR(read_pose_json((dir / "p.json").string()).yaw_deg(), -30.0, 1e-9);
  std::ofstream(dir / "bad.json") << R"({"x": 1, "y": "two", "z": 0})";
  EXPECT_THROW(read_pose_json((dir / "bad.json").string()), ScanReadError);
  EXPECT_THROW(read_scans((dir / "missing.pcd").string()), ScanReadError);
  std::ofstream(dir / "x.las") << "";
  try {
    read_scans((dir / "x.las").string());
    FAIL();
  } catch (const ScanReadError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown point cloud format"), std::string::npos);
  }
  std::ofstream(dir / "junk.pcd") << "not a pcd";
  EXPECT_THROW(read_scans((dir / "junk.pcd").string()), ScanReadError);
}

// Point by point against PCL's own loader: the valid points in file order,
// the NaN/Inf ones dropped and counted.
TEST(ScanIo, ReadsTheRealScan) {
  const std::string path = std::string(SEMIOCTREE_SOURCE_DIR) + "/tests/data/room_scan1.pcd";
  const auto scans = read_scans(path);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].points->size() + scans[0].invalid_dropped, 112586u);
  Cloud pcl_cloud;
  ASSERT_EQ(pcl::io::loadPCDFile(path, pcl_cloud), 0);
  ASSERT_EQ(pcl_cloud.size(), 112586u);
  const Cloud& ours = *scans[0].points;
  std::size_t next = 0, invalid = 0;
  for (std::size_t i = 0; i < pcl_cloud.size(); ++i) {
    const pcl::PointXYZ& p = pcl_cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      ++invalid;
      continue;
    }
    ASSERT_LT(next, ours.size()) << "file point " << i;
    EXPECT_EQ(ours[next].x, p.x) << "file point " << i;
    EXPECT_EQ(ours[next].y, p.y) << "file point " << i;
    EXPECT_EQ(ours[next].z, p.z) << "file point " << i;
    ++next;
  }
  EXPECT_EQ(next, ours.size());
  EXPECT_EQ(invalid, scans[0].invalid_dropped);
  // VIEWPOINT 0 0 0 1 0 0 0: the identity, so no pose from the file.
  EXPECT_EQ(scans[0].pose_from_file,
            !(pcl_cloud.sensor_origin_.head<3>().isZero() &&
              pcl_cloud.sensor_orientation_.isApprox(Eigen::Quaternionf::Identity())));
}

}  // namespace
}  // namespace semioctree

namespace semioctree {
namespace {

// Truncated clouds are an error naming the file, never a crash.
TEST(ScanIo, TruncatedFilesAreRejected) {
  const auto dir = testing::temp_dir("trunc-cloud");
  const std::string real = std::string(SEMIOCTREE_SOURCE_DIR) + "/tests/data/room_scan1.pcd";
  Cloud c;
  for (int i = 0; i < 2000; ++i) c.push_back(pcl::PointXYZ{float(i), float(i % 7), float(i % 3)});
  pcl::io::savePCDFileBinary((dir / "b.pcd").string(), c);
  pcl::io::savePLYFileBinary((dir / "b.ply").string(), c);
  for (const std::string& src : {real, (dir / "b.pcd").string(), (dir / "b.ply").string()}) {
    std::ifstream in(src, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const std::string ext = src.substr(src.size() - 4);
    const auto cut = dir / ("cut" + ext);
    int rejected = 0;
    for (int i = 0; i < 60; ++i) {
      const std::size_t len = bytes.size() * std::size_t(i) / 60;
      std::ofstream(cut, std::ios::binary | std::ios::trunc)
          .write(bytes.data(), std::streamsize(len));
      try {
        read_scans(cut.string());
      } catch (const ScanReadError& e) {
        EXPECT_NE(std::string(e.what()).find(cut.string()), std::string::npos) << e.what();
        ++rejected;
      }
    }
    EXPECT_EQ(rejected, 60) << src;
  }
}

}  // namespace
}  // namespace semioctree

namespace semioctree {
namespace {

// Headers whose counts the file cannot hold, or that PCL would misread: each
// is a ScanReadError naming the file and the problem, found before PCL
// allocates what the header claims (run under `ulimit -v` to be sure).
std::string write_file(const std::filesystem::path& dir, const std::string& name,
                       const std::string& bytes) {
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

void expect_rejected(const std::string& path, const std::string& problem) {
  SCOPED_TRACE(path);
  const auto start = std::chrono::steady_clock::now();
  try {
    read_scans(path);
    ADD_FAILURE() << "accepted";
  } catch (const ScanReadError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path + ":"), std::string::npos) << message;
    EXPECT_NE(message.find(problem), std::string::npos) << message;
  }
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  EXPECT_LT(took.count(), 2.0);
}

std::string pcd_header(const std::string& width, const std::string& height,
                       const std::string& points, const std::string& data) {
  return "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " +
         width + "\nHEIGHT " + height + "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + points + "\nDATA " +
         data + "\n";
}

std::string ply_header(const std::string& format, const std::string& vertices) {
  return "ply\nformat " + format + " 1.0\nelement vertex " + vertices +
         "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
}

TEST(ScanIoHeaders, HugePcdPointCountFailsFast) {
  const auto dir = testing::temp_dir("huge-pcd");
  const std::string big = "2000000000";
  expect_rejected(write_file(dir, "bin.pcd", pcd_header(big, "1", big, "binary")),
                  "2000000000 points need 24000000000 data bytes, the file has 0");
  expect_rejected(
      write_file(dir, "bin36.pcd", pcd_header(big, "1", big, "binary") + std::string(36, '\0')),
      "the file has 36");
  expect_rejected(write_file(dir, "ascii.pcd", pcd_header(big, "1", big, "ascii") + "1 2 3\n"),
                  "2000000000 points need at least 11999999999 bytes of ASCII data");
  expect_rejected(
      write_file(dir, "over.pcd", pcd_header("99999999999", "1", "99999999999", "binary")),
      "WIDTH 99999999999 is more than the 2147483647 points");
  // Compressed sizes that agree with the header, but 8 bytes of LZF cannot
  // expand to 1.2 MB.
  std::string block(16, '\0');
  const std::uint32_t sizes[2] = {8, 100000 * 12};
  std::memcpy(block.data(), sizes, sizeof(sizes));
  expect_rejected(
      write_file(dir, "lzf.pcd", pcd_header("100000", "1", "100000", "binary_compressed") + block),
      "8 compressed bytes cannot hold 100000 points");
  std::filesystem::remove_all(dir);
}

TEST(ScanIoHeaders, HugePlyVertexCountFailsFast) {
  const auto dir = testing::temp_dir("huge-ply");
  expect_rejected(write_file(dir, "bin.ply", ply_header("binary_little_endian", "2000000000")),
                  "(vertex 2000000000) need at least 24000000000 data bytes, the file has 0");
  expect_rejected(write_file(dir, "ascii.ply", ply_header("ascii", "2000000000") + "1 2 3\n"),
                  "(vertex 2000000000) need at least 11999999999 bytes of ASCII data");
  for (const char* format : {"ascii", "binary_little_endian"})
    expect_rejected(
        write_file(dir, std::string(format) + "-over.ply", ply_header(format, "99999999999")),
        "element vertex 99999999999 is more than the 2147483647 points");
  expect_rejected(write_file(dir, "neg.ply", ply_header("ascii", "-5") + "1 2 3\n"),
                  "COUNT a non-negative integer, got 'element vertex -5'");
  expect_rejected(write_file(dir, "zero.ply", ply_header("ascii", "0")),
                  "holds no points (element vertex 0)");
  // Counts of other elements are allocated too (PCL reserves range_grid rows).
  expect_rejected(
      write_file(dir, "grid.ply",
                 "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
                 "property float y\nproperty float z\nelement range_grid 99999999999\n"
                 "property list uchar int vertex_indices\nend_header\n" +
                     std::string(12, '\0')),
      "(vertex 1, range_grid 99999999999) need at least");
  std::filesystem::remove_all(dir);
}

TEST(ScanIoHeaders, PcdCountsMustBePositiveAndAgree) {
  const auto dir = testing::temp_dir("pcd-counts");
  const std::string data = "DATA ascii\n1 2 3\n";
  auto pcd = [&](const char* name, const char* w, const char* h, const char* n) {
    return write_file(dir, name, pcd_header(w, h, n, "ascii") + "1 2 3\n");
  };
  expect_rejected(pcd("neg.pcd", "-5", "1", "-5"), "WIDTH must be a positive integer, got '-5'");
  expect_rejected(pcd("zero.pcd", "0", "1", "0"), "WIDTH must be a positive integer, got '0'");
  expect_rejected(pcd("text.pcd", "abc", "1", "1"), "WIDTH must be a positive integer, got 'abc'");
  expect_rejected(pcd("height.pcd", "1", "0", "1"), "HEIGHT must be a positive integer");
  expect_rejected(pcd("points.pcd", "1", "1", "-1"), "POINTS must be a positive integer");
  expect_rejected(pcd("product.pcd", "3", "2", "5"),
                  "WIDTH x HEIGHT (3 x 2) is not its POINTS (5)");
  expect_rejected(
      write_file(dir, "nopoints.pcd", "VERSION 0.7\nFIELDS x y z\nWIDTH 1\nHEIGHT 1\n" + data),
      "no POINTS");
  expect_rejected(
      write_file(dir, "order.pcd", "VERSION 0.7\nFIELDS x y z\nPOINTS 1\nWIDTH 1\n" + data),
      "line 4: WIDTH is repeated or out of order");
  std::filesystem::remove_all(dir);
}

TEST(ScanIoHeaders, PcdAsciiJunkIsRejectedNamingTheLine) {
  const auto dir = testing::temp_dir("pcd-junk");
  const std::string header = pcd_header("2", "1", "2", "ascii");  // 11 lines
  expect_rejected(write_file(dir, "junk.pcd", header + "1 2 3\nabc def ghi\n"),
                  "junk.pcd:13: expected 3 numbers (the header's FIELDS and COUNT), got "
                  "'abc def ghi'");
  expect_rejected(write_file(dir, "short.pcd", header + "1 2\n4 5 6\n7 8 9\n"),
                  "short.pcd:12: expected");
  expect_rejected(write_file(dir, "long.pcd", header + "1 2 3\n\n4 5 6 7\n"), "long.pcd:14:");
  expect_rejected(write_file(dir, "suffix.pcd", header + "1.5abc 2 3\n4 5 6\n"), "got '1.5abc");
  expect_rejected(write_file(dir, "comment.pcd", header + "# two points\n1 2 3\n4 5 6\n"),
                  "comment.pcd:12:");
  expect_rejected(write_file(dir, "cut.pcd", header + "1 2 3\n"),
                  "truncated or its POINTS is wrong");
  expect_rejected(write_file(dir, "cut2.pcd", header + "1 2 3\n\n\n\n\n\n"),
                  "truncated (1 of 2 points)");
  // NaN and Inf are numbers: dropped and counted, as in binary files. Blank
  // lines, extra blanks, CRLF and lines past POINTS are what PCL accepts too.
  const auto path =
      write_file(dir, "ok.pcd",
                 pcd_header("4", "1", "4", "ascii") +
                     "1  2 3\r\n\nnan 0 0\n 4\tinf +6 \n-1e0 .5 2.\nthe end, ignored by PCL\n");
  const auto scans = read_scans(path);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].points->size(), 2u);
  EXPECT_EQ(scans[0].invalid_dropped, 2u);
  EXPECT_FLOAT_EQ((*scans[0].points)[1].y, 0.5f);
  std::filesystem::remove_all(dir);
}

TEST(ScanIoHeaders, HeadersPclWouldMisreadAreRejected) {
  const auto dir = testing::temp_dir("misread");
  // PCL's header loop reads on past DATA: this POINTS would replace the checked one.
  expect_rejected(write_file(dir, "after.pcd",
                             pcd_header("1", "1", "1", "binary") + "POINTS 2000000000\n" +
                                 std::string(12, '\0')),
                  "PCD header entry after the DATA line");
  expect_rejected(write_file(dir, "long.pcd",
                             "VERSION 0.7\n" + std::string(70000, '#') + "\n" +
                                 pcd_header("1", "1", "1", "ascii") + "1 2 3\n"),
                  "PCD header is longer than 64 KiB");
  expect_rejected(write_file(dir, "text.pcd", "not a pcd"), "not a PCD header entry");
  expect_rejected(write_file(dir, "text.ply", "ply\nformat ascii 1.0\n"), "no end_header");
  // PCL converts coordinates of another type to 0.
  expect_rejected(write_file(dir, "double.pcd",
                             "FIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n"),
                  "PCD field x is not a 4-byte float");
  expect_rejected(
      write_file(dir, "double.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
                 "property double z\nend_header\n1 2 3\n"),
      "PLY vertex property x is double, not float");
  expect_rejected(
      write_file(dir, "list.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nproperty list uint float h\nend_header\n1 2 3 1 4\n"),
      "list property in the vertex element is not supported");
  // PCL sizes its buffer by obj_info num_cols x num_rows, and sets the cloud's
  // size from a camera element after reading the vertices.
  expect_rejected(write_file(dir, "objinfo.ply",
                             "ply\nformat ascii 1.0\nobj_info num_cols 20000\n"
                             "obj_info num_rows 20000\nelement vertex 1\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n1 2 3\n"),
                  "obj_info num_cols x num_rows (20000 x 20000) is not the vertex count 1");
  expect_rejected(
      write_file(dir, "camera.ply",
                 "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nelement camera 1\nproperty int viewportx\n"
                 "property int viewporty\nend_header\n1 2 3\n200000000 1\n"),
      "cloud size, 200000000 x 1 points, does not match its data (1 points)");
  std::filesystem::remove_all(dir);
}

// Every layout PCL's writers produce still reads, NaN points dropped and counted.
TEST(ScanIoHeaders, PclWrittenFilesStillRead) {
  const auto dir = testing::temp_dir("pcl-written");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Cloud c;
  for (int i = 0; i < 2000; ++i)
    c.push_back(i % 10 == 3 ? pcl::PointXYZ{nan, nan, nan}
                            : pcl::PointXYZ{float(i), float(i % 7) - 3.f, 0.25f * float(i % 3)});
  c.is_dense = false;
  pcl::PLYWriter ply;
  for (const bool organized : {false, true}) {
    c.width = organized ? 40 : 2000;
    c.height = organized ? 50 : 1;
    const std::string o = organized ? "org-" : "";
    pcl::io::savePCDFileASCII((dir / (o + "a.pcd")).string(), c);
    pcl::io::savePCDFileBinary((dir / (o + "b.pcd")).string(), c);
    pcl::io::savePCDFileBinaryCompressed((dir / (o + "c.pcd")).string(), c);
    pcl::io::savePLYFileASCII((dir / (o + "a.ply")).string(), c);
    pcl::io::savePLYFileBinary((dir / (o + "b.ply")).string(), c);
    ply.write((dir / (o + "b-nocam.ply")).string(), c, true, false);
  }
  ply.write((dir / "org-a-nocam.ply").string(), c, false, false);
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    SCOPED_TRACE(entry.path().string());
    const auto scans = read_scans(entry.path().string());
    ASSERT_EQ(scans.size(), 1u);
    EXPECT_EQ(scans[0].points->size(), 1800u);
    EXPECT_EQ(scans[0].points->size() + scans[0].invalid_dropped, 2000u);
    EXPECT_FLOAT_EQ((*scans[0].points)[1].y, -2.f);
    ++files;
  }
  EXPECT_EQ(files, 13u);
  std::filesystem::remove_all(dir);
}

// PCL's binary writer of a PCLPointCloud2 pads the file to a page past the
// data, with zeros: that reads. The same bytes not zero are rows beyond POINTS.
TEST(ScanIoHeaders, PclPagePaddingIsNotRowsBeyondPoints) {
  const auto dir = testing::temp_dir("pcl-padded");
  Cloud c;
  for (int i = 0; i < 2000; ++i) c.push_back(pcl::PointXYZ{float(i), float(i % 7), 0.5f});
  pcl::PCLPointCloud2 blob;
  pcl::toPCLPointCloud2(c, blob);
  const std::string path = (dir / "padded.pcd").string();
  ASSERT_EQ(pcl::PCDWriter().writeBinary(path, blob), 0);
  const std::uint64_t size = std::filesystem::file_size(path);
  ASSERT_GT(size, 2000u * 12 + 200) << "PCL no longer pads: this test has nothing to test";
  EXPECT_EQ(read_scans(path)[0].points->size(), 2000u);
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  in.close();
  std::fill(bytes.end() - 12, bytes.end(), '\x01');
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  expect_rejected(path, "PCD POINTS is less than the file's data rows");
  std::filesystem::remove_all(dir);
}

// PCL's PLY reader writes each vertex property at a running offset, which its
// uchar red, green, blue, alpha and a second vertex element move apart from the
// fields' offsets: the coordinates read wrong, or the last vertex is written
// past the buffer and PCL aborts. Such headers are refused; the layouts PCL
// writes itself read.
TEST(ScanIoHeaders, VertexLayoutsPclWouldMisplaceAreRejected) {
  const auto dir = testing::temp_dir("ply-layout");
  const std::string head = "ply\nformat ascii 1.0\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const std::string v2 = "element vertex 2\n";
  const std::string grid = "element range_grid 1\nproperty list uchar int vertex_indices\n";
  struct Case {
    const char* name;
    std::string header;  // between the format line and end_header
    const char* data;
    const char* problem;
  };
  const Case cases[] = {
      {"blue.ply", v2 + xyz + "property uchar blue\nproperty double d\n", "1 2 3 4 5\n6 7 8 9 10\n",
       "PLY vertex property blue is out of place"},
      {"split.ply",
       v2 + "property uchar red\n" + xyz + "property uchar green\nproperty uchar blue\n",
       "9 1 2 3 9 9\n9 4 5 6 9 9\n", "PLY vertex property green is out of place"},
      {"red.ply", v2 + xyz + "property uchar red\nproperty uchar green\n", "1 2 3 9 9\n4 5 6 9 9\n",
       "PLY vertex has red without all of red, green, blue"},
      {"alpha.ply", v2 + xyz + "property float rgb\nproperty uchar alpha\n",
       "1 2 3 0 255\n4 5 6 0 255\n", "PLY vertex property alpha comes before red, green, blue"},
      {"twice.ply", v2 + xyz + "property float x\n", "1 2 3 4\n5 6 7 8\n",
       "PLY header line 7: vertex property x is declared twice"},
      {"second.ply", v2 + xyz + v2 + xyz, "1 2 3\n4 5 6\n7 8 9\n1 2 3\n",
       "PLY header line 7: a second vertex element"},
      {"grids.ply", "element vertex 1\n" + xyz + grid + grid, "1 2 3\n1 0\n1 0\n",
       "PLY header line 9: a second range_grid element"},
      {"grid.ply",
       "obj_info num_cols 1\nobj_info num_rows 1\n" + v2 + xyz + "property double d\n" + grid,
       "1 2 3 4\n5 6 7 8\n1 0\n", "PLY has more vertices (2) than range_grid cells (1)"},
  };
  for (const Case& c : cases)
    expect_rejected(write_file(dir, c.name, head + c.header + "end_header\n" + c.data), c.problem);

  // Colours as PCL writes them, and by hand with alpha, still read.
  pcl::PointCloud<pcl::PointXYZRGBA> coloured;
  for (int i = 0; i < 50; ++i) {
    pcl::PointXYZRGBA p;
    p.x = float(i);
    p.y = -float(i);
    p.z = 0.5f;
    p.r = 200;
    p.g = std::uint8_t(i);
    p.b = 7;
    p.a = 255;
    coloured.push_back(p);
  }
  pcl::io::savePLYFileASCII((dir / "pcl-a.ply").string(), coloured);
  pcl::io::savePLYFileBinary((dir / "pcl-b.ply").string(), coloured);
  write_file(dir, "hand.ply",
             head + v2 + xyz +
                 "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                 "property uchar alpha\nproperty float w\nend_header\n"
                 "1 2 3 9 9 9 255 -1\n4 5 6 9 9 9 255 -1\n");
  for (const std::string name : {"pcl-a.ply", "pcl-b.ply", "hand.ply"}) {
    SCOPED_TRACE(name);
    const auto scans = read_scans((dir / name).string());
    ASSERT_EQ(scans.size(), 1u);
    const Cloud& c = *scans[0].points;
    const bool hand = name == "hand.ply";
    ASSERT_EQ(c.size(), hand ? 2u : 50u);
    EXPECT_EQ(c.back().getVector3fMap(),
              hand ? Eigen::Vector3f(4, 5, 6) : Eigen::Vector3f(49, -49, 0.5f));
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace semioctree
