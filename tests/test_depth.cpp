// Real sensor input (SEMANTICS.md "Real sensor input"): depth images back-projected by hand,
// integrated as the clouds they stand for, 16-bit PNGs and TUM RGB-D folders written and read
// back, and the timestamp rule.
#include "nbv/errors.hpp"
#include "nbv/grid/depth_image.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/depth_io.hpp"

#include "dataset_like.hpp"
#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>

namespace nbv {
namespace {

using grid::DepthImage;
using grid::DepthOptions;
using grid::NoReturn;
using grid::OccupancyMap;

void expectSameMaps(const OccupancyMap& a, const OccupancyMap& b) {
  const auto va = a.measuredVoxels(), vb = b.measuredVoxels();
  ASSERT_EQ(va.size(), vb.size());
  for (std::size_t i = 0; i < va.size(); ++i) {
    ASSERT_EQ(va[i].ijk, vb[i].ijk);
    ASSERT_EQ(va[i].log_odds, vb[i].log_odds);
  }
  const auto ma = a.proximityMarks(), mb = b.proximityMarks();
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i) {
    ASSERT_EQ(ma[i].ijk, mb[i].ijk);
    ASSERT_EQ(ma[i].distance, mb[i].distance);
  }
}

TEST(DepthImages, BackProjectionByHand) {
  const sensor::PinholeCamera camera{4, 3, 2.0, 4.0, 1.5, 1.0};
  std::vector<std::uint16_t> raw(12, 0);
  raw[1 * 4 + 3] = 10000;  // pixel (u 3, v 1) at 2 m (5000 per metre)
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  const auto points = grid::backProject(DepthImage{4, 3, raw, {}}, camera, T, DepthOptions{});
  ASSERT_EQ(points.size(), 1u);
  // z ((u - cx) / fx, (v - cy) / fy, 1) = 2 (0.75, 0, 1), then the pose.
  EXPECT_EQ(points[0], Eigen::Vector3f(1.0f + 1.5f, 2.0f, 3.0f + 2.0f));
  // The same in float metres; NaN and 0 are no return, and under Clear they clear up to their distance.
  std::vector<float> metres(12, 0.0f);
  metres[1 * 4 + 3] = 2.0f;
  metres[0] = std::nanf("");
  DepthOptions clear;
  clear.no_return = NoReturn::Clear;
  clear.no_return_distance_m = 5.0;
  const auto cleared = grid::backProject(DepthImage{4, 3, {}, metres}, camera, T, clear);
  ASSERT_EQ(cleared.size(), 12u);
  EXPECT_EQ(cleared[0], points[0]);  // the hits first
  const Eigen::Vector3d corner = Eigen::Vector3d((0 - 1.5) / 2.0, (0 - 1.0) / 4.0, 1.0).normalized() * 5.0;
  EXPECT_TRUE(cleared[1].isApprox((T * corner).cast<float>(), 1e-6f));  // pixel (0, 0) at 5 m
  // Refused: another size, both kinds or none, a zero scale, a scaled pose.
  EXPECT_THROW(grid::backProject(DepthImage{3, 4, raw, {}}, camera, T, DepthOptions{}), InvalidArgument);
  EXPECT_THROW(grid::backProject(DepthImage{4, 3, raw, metres}, camera, T, DepthOptions{}), InvalidArgument);
  EXPECT_THROW(grid::backProject(DepthImage{4, 3, {}, {}}, camera, T, DepthOptions{}), InvalidArgument);
  DepthOptions zero;
  zero.scale = 0.0;
  EXPECT_THROW(grid::backProject(DepthImage{4, 3, raw, {}}, camera, T, zero), InvalidArgument);
  Eigen::Isometry3d scaled = T;
  scaled.linear() *= 2.0;
  EXPECT_THROW(grid::backProject(DepthImage{4, 3, raw, {}}, camera, scaled, DepthOptions{}), InvalidArgument);
}

/// The bunny rendered from a dome view as a 16-bit image (5000 per metre), and its pose.
struct Frame {
  sensor::DepthPng png;
  Eigen::Isometry3d T_world_camera;
};

std::vector<Frame> renderedFrames(const std::vector<int>& indices) {
  sensor::TriangleMesh mesh = test::sphereMesh({0.0f, 0.0f, 0.2f}, 0.2f, 40);
  const sensor::RayScene scene(mesh);
  const sensor::DepthCamera camera;
  std::vector<Frame> frames;
  for (const int i : indices) {
    const Eigen::Isometry3d T = planner::dome48()[static_cast<std::size_t>(i)].T_world_camera;
    const sensor::DepthScan scan = camera.render(scene, T);
    Frame f{{scan.width, scan.height, std::vector<std::uint16_t>(scan.depth_m.size(), 0)}, T};
    for (std::size_t p = 0; p < scan.depth_m.size(); ++p) {
      f.png.values[p] = static_cast<std::uint16_t>(std::lround(scan.depth_m[p] * 5000.0f));
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

TEST(DepthImages, IntegratingAFrameIsIntegratingItsCloud) {
  const sensor::PinholeCamera camera;
  for (const NoReturn no_return : {NoReturn::Drop, NoReturn::Clear}) {
    OccupancyMap by_depth, by_cloud;
    for (const Frame& f : renderedFrames({0, 21})) {
      const DepthImage image{f.png.width, f.png.height, f.png.values, {}};
      DepthOptions options;
      options.no_return = no_return;
      by_depth.integrateDepth(image, camera, f.T_world_camera, options);
      options.no_return_distance_m = 2.0 * by_cloud.config().max_range;
      by_cloud.integrate(grid::backProject(image, camera, f.T_world_camera, options), f.T_world_camera.translation().cast<float>());
    }
    expectSameMaps(by_depth, by_cloud);
    EXPECT_GT(by_depth.octomapOccupiedCount(), 1000u);
  }
}

TEST(DepthImages, ANegativeFocalLengthFlipsItsAxis) {
  // A frame stored upside down (row v holds row H - 1 - v) under fy' = -fy, cy' = H - 1 - cy, as
  // ICL-NUIM publishes its intrinsics, gives every pixel the ray it had: the same map.
  const sensor::PinholeCamera camera;
  sensor::PinholeCamera flipped = camera;
  flipped.fy = -camera.fy;
  flipped.cy = camera.height - 1 - camera.cy;
  OccupancyMap upright, upside_down;
  for (const Frame& f : renderedFrames({0, 21})) {
    std::vector<std::uint16_t> rows(f.png.values.size());
    const auto width = static_cast<std::size_t>(f.png.width), height = static_cast<std::size_t>(f.png.height);
    for (std::size_t v = 0; v < height; ++v) {
      std::copy_n(f.png.values.begin() + static_cast<std::ptrdiff_t>(v * width), width,
                  rows.begin() + static_cast<std::ptrdiff_t>((height - 1 - v) * width));
    }
    upright.integrateDepth(DepthImage{f.png.width, f.png.height, f.png.values, {}}, camera, f.T_world_camera);
    upside_down.integrateDepth(DepthImage{f.png.width, f.png.height, rows, {}}, flipped, f.T_world_camera);
  }
  expectSameMaps(upright, upside_down);
  EXPECT_GT(upright.octomapOccupiedCount(), 1000u);
  // Zero has no ray.
  sensor::PinholeCamera zero = camera;
  zero.fx = 0.0;
  EXPECT_THROW(zero.validate(), InvalidArgument);
}

TEST(DepthImages, ADatasetLikeSequenceNeedsItsRangeAndBuildsTheScene) {
  // Noisy, holey, upside-down frames of a room-scale scene 2-3 m away, read back from a
  // numbered folder and a pose file without timestamps, as datasets ship them.
  const test::DatasetLikeSequence sequence(6);
  const sensor::PinholeCamera camera = test::DatasetLikeSequence::camera();
  test::TempDir dir;
  std::filesystem::create_directories(dir / "depth");
  std::ofstream poses(dir / "poses.txt");
  for (std::size_t f = 0; f < sequence.depth.size(); ++f) {
    sensor::writeDepthPng16(dir / "depth" / ("frame_" + std::to_string(f) + ".png"), camera.width, camera.height, sequence.depth[f]);
    const Eigen::Quaterniond q(sequence.T_world_camera[f].linear());
    const Eigen::Vector3d t = sequence.T_world_camera[f].translation();
    poses << std::setprecision(17) << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' '
          << q.w() << '\n';
  }
  poses.close();
  const std::vector<sensor::TumFrame> frames = sensor::readFrameFolder(dir / "depth", dir / "poses.txt");
  ASSERT_EQ(frames.size(), sequence.depth.size());
  OccupancyMap::Config room_config;
  room_config.resolution = 0.02;
  room_config.max_range = 3.0;
  OccupancyMap::Config default_range = room_config;
  default_range.max_range = OccupancyMap::Config{}.max_range;
  OccupancyMap room(room_config), cut(default_range);
  grid::ScanStats room_stats, cut_stats;
  std::size_t returns = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const sensor::DepthPng png = sensor::readDepthPng16(frames[f].depth_file);
    ASSERT_EQ(png.values, sequence.depth[f]);
    EXPECT_TRUE(frames[f].T_world_camera.isApprox(sequence.T_world_camera[f], 1e-12));
    const DepthImage image{png.width, png.height, png.values, {}};
    room_stats += room.integrateDepth(image, camera, frames[f].T_world_camera);
    cut_stats += cut.integrateDepth(image, camera, frames[f].T_world_camera);
    returns += static_cast<std::size_t>(std::count_if(png.values.begin(), png.values.end(), [](std::uint16_t d) { return d > 0; }));
  }
  // Holes give nothing; every return is a point. At 1.5 m nothing of the scene is hit.
  EXPECT_EQ(room_stats.points, returns);
  EXPECT_LT(returns, 0.97 * 6 * 640 * 480);
  EXPECT_EQ(cut_stats.hits, 0u);
  EXPECT_GT(room_stats.hits, returns / 2);
  // Under 3 m the occupied voxels lie on the ball and the ground, within the noise (sigma about
  // 1 cm at 2.5 m) and a voxel's half diagonal.
  std::size_t occupied = 0, near_surface = 0;
  for (const grid::MeasuredVoxel& v : room.measuredVoxels()) {
    if (v.log_odds <= 0.0f) continue;
    ++occupied;
    near_surface += test::DatasetLikeSequence::surfaceDistance(room.indexToWorld(v.ijk)) < 0.05;
  }
  EXPECT_GT(occupied, 5000u);
  EXPECT_GT(static_cast<double>(near_surface), 0.97 * static_cast<double>(occupied)) << near_surface << " of " << occupied;
}

TEST(DepthImages, PngsRoundTripEveryValue) {
  test::TempDir dir;
  std::vector<std::uint16_t> values(7 * 5);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = static_cast<std::uint16_t>(i * 1871 + (i % 3) * 60000);
  sensor::writeDepthPng16(dir / "d.png", 7, 5, values);
  const sensor::DepthPng back = sensor::readDepthPng16(dir / "d.png");
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  EXPECT_EQ(back.values, values);
  EXPECT_THROW(sensor::writeDepthPng16(dir / "e.png", 7, 4, values), InvalidArgument);
}

TEST(DepthImages, ARenderedSequenceFromItsTumFolderIsTheSequenceOfClouds) {
  test::TempDir dir;
  const std::vector<Frame> frames = renderedFrames({0, 5, 17, 30, 41});
  std::vector<sensor::DepthPng> pngs;
  std::vector<Eigen::Isometry3d> poses;
  for (const Frame& f : frames) {
    pngs.push_back(f.png);
    poses.push_back(f.T_world_camera);
  }
  sensor::writeTumSequence(dir.path(), pngs, poses);
  const sensor::PinholeCamera camera;
  OccupancyMap from_folder, from_clouds;
  const std::vector<sensor::TumFrame> sequence = sensor::readTumSequence(dir.path());
  ASSERT_EQ(sequence.size(), frames.size());
  for (const sensor::TumFrame& frame : sequence) {
    const sensor::DepthPng png = sensor::readDepthPng16(frame.depth_file);
    from_folder.integrateDepth(DepthImage{png.width, png.height, png.values, {}}, camera, frame.T_world_camera);
  }
  for (const Frame& f : frames) {
    const auto cloud = grid::backProject(DepthImage{f.png.width, f.png.height, f.png.values, {}}, camera, f.T_world_camera,
                                         DepthOptions{});
    from_clouds.integrate(cloud, f.T_world_camera.translation().cast<float>());
  }
  expectSameMaps(from_folder, from_clouds);
  EXPECT_DOUBLE_EQ(sequence[1].timestamp, 1.1);
}

TEST(DepthImages, AFrameTakesTheNearestPoseWithin20Ms) {
  test::TempDir dir;
  sensor::writeDepthPng16(dir / "d.png", 2, 2, std::vector<std::uint16_t>(4, 5000));
  std::ofstream(dir / "depth.txt") << "1.000 d.png\n";
  std::ofstream(dir / "groundtruth.txt") << "0.985 1 0 0 0 0 0 1\n1.012 2 0 0 0 0 0 1\n1.500 3 0 0 0 0 0 1\n";
  const auto frames = sensor::readTumSequence(dir.path());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].T_world_camera.translation().x(), 2.0);  // 12 ms beats 15 ms
  std::ofstream(dir / "groundtruth.txt") << "0.975 1 0 0 0 0 0 1\n1.025 2 0 0 0 0 0 1\n";
  try {
    sensor::readTumSequence(dir.path());
    FAIL() << "no error";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("depth.txt: line 1: frame at 1.000000 s has no pose within 20 ms"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace nbv
