// PLY point clouds: every encoding the reader accepts, and the files it must refuse.
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include "expect_file_error.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

namespace {

using nbv::CloudFileError;
namespace fs = std::filesystem;

using nbv::test::writeBytes;

template <class T>
void append(std::string& out, T value, bool big_endian = false) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big_endian) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

TEST(PinholeCamera, DefaultsAreSpecSection2) {
  const nbv::sensor::PinholeCamera camera;
  EXPECT_EQ(camera.width, 752);
  EXPECT_EQ(camera.height, 480);
  EXPECT_EQ(camera.fx, 448.1008985853343);
  EXPECT_EQ(camera.cx, 376.5);
  EXPECT_EQ(camera.cy, 240.5);
  // The principal point's ray is the optical axis; a pixel fx to the right is 45 degrees.
  EXPECT_TRUE(camera.rayDirectionCamera(376.5, 240.5).isApprox(Eigen::Vector3d(0, 0, 1)));
  const Eigen::Vector3d d = camera.rayDirectionCamera(376.5 + camera.fx, 240.5);
  EXPECT_NEAR(d.x(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(d.z(), std::sqrt(0.5), 1e-12);
}

TEST(PlyCloud, BinaryRoundTrip) {
  nbv::test::TempDir dir;
  const std::vector<Eigen::Vector3f> points = {{0.1f, -2.f, 3.5f}, {1e-3f, 7.f, -0.25f}};
  nbv::sensor::writePlyCloud(dir / "c.ply", points);
  EXPECT_EQ(nbv::sensor::readPlyCloud(dir / "c.ply"), points);
}

TEST(PlyCloud, AsciiWithExtraPropertiesAndFaces) {
  nbv::test::TempDir dir;
  writeBytes(dir / "a.ply",
             "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nelement vertex 2\r\n"
             "property double x\r\nproperty uchar red\r\nproperty double y\r\nproperty float z\r\n"
             "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
             "1.5 255 2.5 -3\r\nnan 0 inf 4\r\n3 0 1 1\r\n");
  const auto points = nbv::sensor::readPlyCloud(dir / "a.ply");
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0], Eigen::Vector3f(1.5f, 2.5f, -3.f));
  EXPECT_TRUE(std::isnan(points[1].x()));  // kept: integration skips non-finite points
  EXPECT_TRUE(std::isinf(points[1].y()));
}

TEST(PlyCloud, BigEndianDoublesAfterAnotherElement) {
  nbv::test::TempDir dir;
  std::string ply = "ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty float f\n"
                    "property list uchar short ids\nelement vertex 1\nproperty double z\n"
                    "property double y\nproperty double x\nend_header\n";
  append(ply, 9.0f, true);
  append<std::uint8_t>(ply, 2);
  append<std::int16_t>(ply, 1, true);
  append<std::int16_t>(ply, 2, true);
  append(ply, 3.0, true);
  append(ply, 2.0, true);
  append(ply, 1.0, true);
  writeBytes(dir / "b.ply", ply);
  const auto points = nbv::sensor::readPlyCloud(dir / "b.ply");
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0], Eigen::Vector3f(1.f, 2.f, 3.f));
}

void expectRefused(const fs::path& path, const std::string& fragment) {
  nbv::test::expectFileError<CloudFileError>(path, [](const fs::path& p) { nbv::sensor::readPlyCloud(p); }, fragment);
}

TEST(PlyCloud, BadFilesAreRefusedNamingFileAndProblem) {
  nbv::test::TempDir dir;
  const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
                             "property float x\nproperty float y\nproperty float z\nend_header\n";
  std::string good = header;
  for (int i = 0; i < 6; ++i) append(good, 0.5f * static_cast<float>(i));

  expectRefused(dir / "missing.ply", "no such file");
  fs::create_directory(dir / "dir.ply");
  expectRefused(dir / "dir.ply", "directory");
  writeBytes(dir / "empty.ply", "");
  expectRefused(dir / "empty.ply", "empty");
  writeBytes(dir / "magic.ply", "plx\nformat ascii 1.0\n");
  expectRefused(dir / "magic.ply", "not a PLY");
  writeBytes(dir / "cut_header.ply", header.substr(0, 40));
  expectRefused(dir / "cut_header.ply", "end_header");
  for (std::size_t cut : {header.size(), header.size() + 5, good.size() - 1}) {
    writeBytes(dir / "cut_data.ply", good.substr(0, cut));
    expectRefused(dir / "cut_data.ply", "truncated");
  }
  writeBytes(dir / "format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n");
  expectRefused(dir / "format.ply", "line 2");
  writeBytes(dir / "noz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                              "property float y\nend_header\n1 2\n");
  expectRefused(dir / "noz.ply", "lacks x, y or z");
  writeBytes(dir / "text.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n1 2 3\n4 five 6\n");
  expectRefused(dir / "text.ply", "line 9");
  writeBytes(dir / "count.ply", "ply\nformat ascii 1.0\nelement vertex -4\nend_header\n");
  expectRefused(dir / "count.ply", "line 3");
  // 10^12 vertices in a small file: refused before any allocation.
  std::string bomb = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\n"
                     "property float x\nproperty float y\nproperty float z\nend_header\n";
  bomb += std::string(64, '\0');
  writeBytes(dir / "bomb.ply", bomb);
  expectRefused(dir / "bomb.ply", "more than the file can hold");
  writeBytes(dir / "noverts.ply", "ply\nformat ascii 1.0\nelement face 0\nend_header\n");
  expectRefused(dir / "noverts.ply", "no 'vertex' element");
}

}  // namespace
