#include "nbv/grid/depth_image.hpp"
#include "nbv/grid/occupancy_map.hpp"

#include "nbv/errors.hpp"

#include <cmath>
#include <limits>
#include <string>

namespace nbv::grid {

NoReturn noReturnFromName(std::string_view name) {
  const std::string n(name);
  if (n == "drop") return NoReturn::Drop;
  if (n == "clear") return NoReturn::Clear;
  throw InvalidArgument("no-return '" + n + "' is not 'drop' or 'clear'");
}

std::vector<Eigen::Vector3f> backProject(const DepthImage& depth, const sensor::PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_world_camera, const DepthOptions& options) {
  camera.validate();
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  if (depth.width != camera.width || depth.height != camera.height) {
    throw InvalidArgument("depth image of " + std::to_string(depth.width) + " x " + std::to_string(depth.height) +
                          " pixels for a camera of " + std::to_string(camera.width) + " x " + std::to_string(camera.height));
  }
  const bool raw = !depth.raw.empty();
  if (raw == !depth.metres.empty() || (raw ? depth.raw.size() : depth.metres.size()) != pixels) {
    throw InvalidArgument("a depth image holds width x height 16-bit values or width x height floats, one of the two");
  }
  if (raw && !(options.scale > 0.0 && std::isfinite(options.scale))) {
    throw InvalidArgument("depth scale " + numberText(options.scale) + " must be a positive number of values per metre");
  }
  if (options.no_return == NoReturn::Clear && !(options.no_return_distance_m > 0.0 && std::isfinite(options.no_return_distance_m))) {
    throw InvalidArgument("no-return distance " + numberText(options.no_return_distance_m) + " m must be positive");
  }
  const Eigen::Matrix3d R = T_world_camera.linear();
  if (!T_world_camera.matrix().allFinite() || (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      R.determinant() <= 0.0) {
    throw InvalidArgument("the depth frame's pose is not a finite rigid transform");
  }
  std::vector<Eigen::Vector3f> points, far;
  points.reserve(pixels);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * static_cast<std::size_t>(camera.width) + static_cast<std::size_t>(u);
      const double z = raw ? static_cast<double>(depth.raw[i]) / options.scale : static_cast<double>(depth.metres[i]);
      // SEMANTICS.md "Real sensor input": the pixel's direction scaled to z = depth.
      const Eigen::Vector3d ray((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      if (z > 0.0 && std::isfinite(z)) {
        points.push_back((T_world_camera * (z * ray)).cast<float>());
      } else if (options.no_return == NoReturn::Clear) {
        far.push_back((T_world_camera * (options.no_return_distance_m * ray.normalized())).cast<float>());
      }
    }
  }
  points.insert(points.end(), far.begin(), far.end());
  return points;
}

ScanStats OccupancyMap::integrateDepth(const DepthImage& depth, const sensor::PinholeCamera& camera,
                                       const Eigen::Isometry3d& T_world_camera, const DepthOptions& depth_options,
                                       const IntegrateOptions& options) {
  DepthOptions o = depth_options;
  o.no_return_distance_m = 2.0 * config_.max_range;  // beyond max_range: its ray clears, no hit
  return integrate(backProject(depth, camera, T_world_camera, o), T_world_camera.translation().cast<float>(), options);
}

}  // namespace nbv::grid
