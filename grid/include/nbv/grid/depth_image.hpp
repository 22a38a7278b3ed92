#pragma once
/// \file Depth images (SEMANTICS.md "Real sensor input"): a frame of z-depths and the points it
/// stands for, which OccupancyMap::integrateDepth() integrates.

#include "nbv/sensor/pinhole_camera.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace nbv::grid {

/// What a pixel that sees nothing (depth 0 or NaN) adds to the map.
enum class NoReturn {
  Drop,   ///< nothing
  Clear,  ///< free space along its ray up to the map's max_range, no hit
};
/// "drop" or "clear". \throws InvalidArgument for another name.
NoReturn noReturnFromName(std::string_view name);

/// One depth frame, row-major, u along the row: z-depth per pixel, either 16-bit values of
/// `DepthOptions::scale` per metre (TUM RGB-D: 5000) or 32-bit float metres. Exactly one of
/// the two spans holds width x height values. A view, not a copy.
struct DepthImage {
  int width = 0;
  int height = 0;
  std::span<const std::uint16_t> raw;  ///< 16-bit depths
  std::span<const float> metres;       ///< float depths [m]
};

/// How a depth frame becomes points.
struct DepthOptions {
  double scale = 5000.0;               ///< 16-bit values per metre
  NoReturn no_return = NoReturn::Drop;
  /// Under Clear, a no-return pixel's point lies this far along its ray [m]: set it beyond the
  /// map's max_range (integrateDepth() takes twice the map's max_range).
  double no_return_distance_m = 3.0;
};

/// The world points of a depth frame taken from T_world_camera (camera -> world) with
/// `camera`: pixel (u, v) of depth z is the camera-frame point z ((u - cx) / fx, (v - cy) / fy, 1)
/// (SEMANTICS.md "Real sensor input"), in row-major order; no-return pixels add nothing, or
/// under Clear the point at no_return_distance_m along their ray, after the others.
/// Thread-safe. \throws InvalidArgument if the image is not the camera's size, holds not
/// exactly one kind of depth, or the scale, distance or pose is unusable.
std::vector<Eigen::Vector3f> backProject(const DepthImage& depth, const sensor::PinholeCamera& camera,
                                         const Eigen::Isometry3d& T_world_camera, const DepthOptions& options);

}  // namespace nbv::grid
