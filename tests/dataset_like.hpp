#pragma once
// A rendered depth sequence that behaves like a public RGB-D dataset's (SEMANTICS.md "Real
// sensor input"): ICL-NUIM's published camera (640 x 480, fx 481.2, fy -480, cx 319.5, cy
// 239.5: rows stored upside down), 16-bit depth at 5000 per metre, axial noise growing with
// depth squared, holes (zero pixels, scattered and in blocks), and a room-scale scene seen from
// 2.2-2.8 m, beyond the map's 1.5 m default range. Shared by tests/test_depth.cpp and
// bench/bench_grid.cpp.

#include "nbv/sensor/depth_camera.hpp"

#include "scenes.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace nbv::test {

struct DatasetLikeSequence {
  /// The scene: a ball of radius 0.5 m resting on the ground plane z = 0.
  static constexpr double kRadius = 0.5;
  static Eigen::Vector3d centre() { return {0.0, 0.0, kRadius}; }
  /// ICL-NUIM's intrinsics as published (a negative fy).
  static sensor::PinholeCamera camera() { return {640, 480, 481.2, -480.0, 319.5, 239.5}; }

  std::vector<std::vector<std::uint16_t>> depth;  ///< per frame, row-major, 0 = no return
  std::vector<Eigen::Isometry3d> T_world_camera;

  /// `frames` views on a circle of 2.4 m around the ball, 1.2 m up; noise sigma(z) = 1.2 mm +
  /// 1.9 mm z^2 (a Kinect-like axial model), 3 % of the pixels dropped at random and one 40 x 40
  /// block per frame, all fixed by `seed`.
  explicit DatasetLikeSequence(int frames, std::uint64_t seed = 1) {
    const sensor::TriangleMesh ball = sphereMesh(centre().cast<float>(), static_cast<float>(kRadius), 48);
    const sensor::RayScene scene(ball, sensor::SceneOptions{true});
    sensor::DepthCameraConfig config;
    config.camera = camera();
    config.max_range_m = 4.0;  // what the sensor returns; the map's own range decides the rest
    config.noise = {sensor::DepthNoise::Kind::AxialGaussian, 0.0012, 0.0019, seed};
    std::mt19937_64 random(seed);
    for (int f = 0; f < frames; ++f) {
      const double angle = 2.0 * M_PI * f / frames;
      const Eigen::Vector3d position(2.4 * std::cos(angle), 2.4 * std::sin(angle), 1.2);
      T_world_camera.push_back(lookAt(position, centre()));
      config.noise.seed = seed + static_cast<std::uint64_t>(f);
      const sensor::DepthScan scan = sensor::DepthCamera(config).render(scene, T_world_camera.back());
      std::vector<std::uint16_t> raw(scan.depth_m.size());
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      for (std::size_t i = 0; i < raw.size(); ++i) {
        const double z = scan.depth_m[i];
        raw[i] = unit(random) < 0.03 || !(z > 0.0) ? 0 : static_cast<std::uint16_t>(std::min(65535.0, std::round(z * 5000.0)));
      }
      const int u0 = static_cast<int>(unit(random) * 600), v0 = static_cast<int>(unit(random) * 440);
      for (int v = v0; v < v0 + 40; ++v) {
        for (int u = u0; u < u0 + 40; ++u) raw[static_cast<std::size_t>(v) * 640 + static_cast<std::size_t>(u)] = 0;
      }
      depth.push_back(std::move(raw));
    }
  }

  /// Distance of a world point to the scene's surface (the ball or the ground) [m].
  static double surfaceDistance(const Eigen::Vector3d& p) {
    return std::min(std::abs((p - centre()).norm() - kRadius), std::abs(p.z()));
  }
};

}  // namespace nbv::test
