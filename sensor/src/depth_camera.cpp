#include "nbv/sensor/depth_camera.hpp"

#include "nbv/fork_join.hpp"

#include "nbv/errors.hpp"

#include <tbb/blocked_range2d.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace nbv::sensor {

namespace {

/// SplitMix64: a counter-based generator, so every pixel draws its own numbers from
/// (seed, pixel) and the noise does not depend on the thread that renders the pixel.
std::uint64_t splitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// A standard normal number for pixel `pixel` (Box-Muller on two SplitMix64 draws).
double standardNormal(std::uint64_t seed, std::uint64_t pixel) {
  const std::uint64_t a = splitMix64(seed ^ splitMix64(2 * pixel));
  const std::uint64_t b = splitMix64(seed ^ splitMix64(2 * pixel + 1));
  const double u1 = (static_cast<double>(a >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
  const double u2 = static_cast<double>(b >> 11) * 0x1.0p-53;          // [0, 1)
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

/// A uniform number in [0, 1) for draw `k` of `seed`.
double uniformDraw(std::uint64_t seed, std::uint64_t k) {
  return static_cast<double>(splitMix64(seed ^ splitMix64(k)) >> 11) * 0x1.0p-53;
}

/// Per pixel, whether DepthHoles drops it: its own draw (below `fraction`), or a square's.
std::vector<bool> holeMask(const DepthHoles& holes, int width, int height) {
  std::vector<bool> dropped(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), false);
  if (holes.fraction > 0.0) {
    for (std::size_t i = 0; i < dropped.size(); ++i) dropped[i] = uniformDraw(holes.seed, 2 * i) < holes.fraction;
  }
  for (int b = 0; b < holes.blocks; ++b) {
    // The squares take odd draws, the pixels the even ones.
    const auto k = static_cast<std::uint64_t>(b);
    // Each square inside the image where it fits.
    const int u0 = static_cast<int>(uniformDraw(holes.seed, 4 * k + 1) * std::max(1, width - holes.block_size + 1));
    const int v0 = static_cast<int>(uniformDraw(holes.seed, 4 * k + 3) * std::max(1, height - holes.block_size + 1));
    for (int v = v0; v < std::min(height, v0 + holes.block_size); ++v) {
      for (int u = u0; u < std::min(width, u0 + holes.block_size); ++u) {
        dropped[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)] = true;
      }
    }
  }
  return dropped;
}

}  // namespace

DepthCamera::DepthCamera(const DepthCameraConfig& config) : config_(config) {
  config_.camera.validate();
  if (!(config_.max_range_m > 0.0) || !std::isfinite(config_.max_range_m)) {
    throw InvalidArgument("depth camera max range must be finite and > 0, got " +
                                numberText(config_.max_range_m));
  }
  if (config_.tile_size < 1) throw InvalidArgument("depth camera tile size must be >= 1");
  const DepthNoise& n = config_.noise;
  if (n.kind == DepthNoise::Kind::AxialGaussian &&
      (!std::isfinite(n.a_m) || !std::isfinite(n.b_per_m) || n.a_m < 0.0 || n.b_per_m < 0.0)) {
    throw InvalidArgument("depth noise needs finite a >= 0 and b >= 0");
  }
  const DepthHoles& h = config_.holes;
  if (!(h.fraction >= 0.0 && h.fraction <= 1.0)) {
    throw InvalidArgument("depth holes: the dropped fraction " + numberText(h.fraction) + " is not in [0, 1]");
  }
  if (h.blocks < 0 || h.block_size < 1) {
    throw InvalidArgument("depth holes: " + std::to_string(h.blocks) + " blocks of " + std::to_string(h.block_size) +
                          " pixels (blocks >= 0, size >= 1)");
  }
}

DepthScan DepthCamera::render(const RayScene& scene, const Eigen::Isometry3d& T_world_camera) const {
  const Eigen::Matrix3d R = T_world_camera.linear();
  if (!T_world_camera.matrix().allFinite() ||
      !(R.transpose() * R).isApprox(Eigen::Matrix3d::Identity(), 1e-6) || R.determinant() < 0.0) {
    throw InvalidArgument("camera pose is not finite or its rotation is not a rotation");
  }
  const PinholeCamera& cam = config_.camera;
  DepthScan scan;
  scan.width = cam.width;
  scan.height = cam.height;
  scan.depth_m.assign(static_cast<std::size_t>(cam.width) * static_cast<std::size_t>(cam.height), 0.0f);
  std::vector<Eigen::Vector3f> pixel_points(scan.depth_m.size());
  std::vector<Surface> pixel_surfaces(scan.depth_m.size(), Surface::Object);
  const Eigen::Vector3f origin = T_world_camera.translation().cast<float>();
  const auto max_range = static_cast<float>(config_.max_range_m);
  const DepthNoise& noise = config_.noise;
  const std::vector<bool> dropped = holeMask(config_.holes, cam.width, cam.height);

  auto render_tile = [&](const tbb::blocked_range2d<int>& tile) {
    for (int v = tile.rows().begin(); v != tile.rows().end(); ++v) {
      for (int u = tile.cols().begin(); u != tile.cols().end(); ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(cam.width) + static_cast<std::size_t>(u);
        if (dropped[i]) continue;  // a hole: no return
        const Eigen::Vector3d ray_camera = cam.rayDirectionCamera(u, v);  // the one pixel -> ray
        const Eigen::Vector3f direction = (R * ray_camera).cast<float>();
        const auto hit = scene.intersect(origin, direction, max_range);
        if (!hit) continue;
        pixel_surfaces[i] = hit->surface;
        double distance = hit->distance_m;
        if (noise.kind == DepthNoise::Kind::AxialGaussian) {
          // Axial noise: the depth z moves by N(0, sigma(z)^2), the point along its ray.
          const double z = distance * ray_camera.z();
          const double sigma = noise.a_m + noise.b_per_m * z * z;
          const double noisy_z = z + sigma * standardNormal(noise.seed, i);
          if (noisy_z <= 0.0) continue;
          distance = noisy_z / ray_camera.z();
        }
        scan.depth_m[i] = static_cast<float>(distance * ray_camera.z());
        pixel_points[i] = origin + static_cast<float>(distance) * direction;
      }
    }
  };
  if (config_.serial) {
    render_tile(tbb::blocked_range2d<int>(0, cam.height, 0, cam.width));
  } else {
    // Tiles handed out by index (TBB reads the index, nbv builds the tile).
    const int tile = config_.tile_size;
    const int columns = (cam.width + tile - 1) / tile;
    const int rows = (cam.height + tile - 1) / tile;
    const auto tile_task = [&](int t) {
      const int v0 = (t / columns) * tile, u0 = (t % columns) * tile;
      render_tile(tbb::blocked_range2d<int>(v0, std::min(cam.height, v0 + tile), u0, std::min(cam.width, u0 + tile)));
    };
    ForkJoin::parallelFor(rows * columns, tile_task);
  }
  // Row-major order whatever the threads did.
  for (std::size_t i = 0; i < scan.depth_m.size(); ++i) {
    if (scan.depth_m[i] > 0.0f) {
      scan.points_world.push_back(pixel_points[i]);
      scan.surfaces.push_back(pixel_surfaces[i]);
    }
  }
  return scan;
}

}  // namespace nbv::sensor
