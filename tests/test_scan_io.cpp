// Scan readers (PCD, PLY, XYZ, PTX) and poses.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "semioctree/scan_io.h"
#include "support/sample_trees.h"

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

TEST(ScanIo, ReadsTheRealScan) {
  const auto scans = read_scans(std::string(SEMIOCTREE_SHARED_DIR) + "/data/real/room_scan1.pcd");
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].points->size() + scans[0].invalid_dropped, 112586u);
}

}  // namespace
}  // namespace semioctree

namespace semioctree {
namespace {

// Truncated clouds are an error naming the file, never a crash.
TEST(ScanIo, TruncatedFilesAreRejected) {
  const auto dir = testing::temp_dir("trunc-cloud");
  const std::string real = std::string(SEMIOCTREE_SHARED_DIR) + "/data/real/room_scan1.pcd";
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
