#pragma once
/// \file Depth images and sequences on disk (SEMANTICS.md "Real sensor input"): 16-bit PNG
/// depth images (TUM RGB-D: 5000 values per metre) and TUM RGB-D style folders.
///
/// Thread-safety: the functions share no state (libpng per call) and may run in several threads at
/// once (two writing one file excepted).

#include "nbv/errors.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace nbv::sensor {

/// A 16-bit depth image, row-major.
struct DepthPng {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> values;
};

/// Reads a 16-bit greyscale PNG. \throws FileError naming the file for a missing, truncated or
/// corrupt file, or one that is not 16-bit greyscale (8-bit, colour, alpha).
DepthPng readDepthPng16(const std::filesystem::path& path);

/// Writes `values` (width x height, row-major) as a 16-bit greyscale PNG.
/// \throws FileError if the file cannot be written; InvalidArgument for a size mismatch.
void writeDepthPng16(const std::filesystem::path& path, int width, int height, std::span<const std::uint16_t> values);

/// Writes an 8-bit greyscale PNG (a picture: width x height bytes, row-major).
/// \throws FileError if the file cannot be written; InvalidArgument for a size mismatch.
void writeGreyPng8(const std::filesystem::path& path, int width, int height, std::span<const std::uint8_t> values);

/// One depth frame of a TUM RGB-D style folder and the pose it was taken from.
struct TumFrame {
  double timestamp = 0.0;            ///< of the depth image [s]
  std::filesystem::path depth_file;  ///< the 16-bit PNG
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

/// The frames of a TUM RGB-D style folder: `depth.txt` lists `timestamp path` per depth image
/// (paths relative to the folder), `groundtruth.txt` lists `timestamp tx ty tz qx qy qz qw`
/// poses of the camera; `#` starts a comment line. Each depth frame takes the pose with the
/// nearest timestamp within `max_offset_s` (20 ms). Both lists must be in increasing time.
/// \throws FileError naming the file and line: a missing list or depth image, an unsorted
/// timestamp, a frame with no pose near enough, a malformed or non-finite line, a zero
/// quaternion.
std::vector<TumFrame> readTumSequence(const std::filesystem::path& folder, double max_offset_s = 0.02);

/// The frames of a numbered image folder and a pose file without timestamps, as several
/// dataset conversions ship them: every `.png` of `folder`, in the order of the last number in
/// its name (frame 2 before frame 10), takes the pose on the same line of `poses`, one
/// `tx ty tz qx qy qz qw` (T_world_camera) per line; `#` starts a comment line.
/// \throws FileError naming the file (and line): no image, two images of one number or an image
/// without one, a malformed or non-finite pose line, a zero quaternion, more or fewer poses
/// than images.
std::vector<TumFrame> readFrameFolder(const std::filesystem::path& folder, const std::filesystem::path& poses);

/// Writes a TUM RGB-D style folder: depth/NNNNNN.png (16-bit, `scale` values per metre) for
/// each image, depth.txt and groundtruth.txt, frame i at time t0 + i * dt.
/// \throws FileError if a file cannot be written; InvalidArgument if the counts differ.
void writeTumSequence(const std::filesystem::path& folder, const std::vector<DepthPng>& depths,
                      const std::vector<Eigen::Isometry3d>& T_world_cameras, double t0 = 1.0, double dt = 0.1);

}  // namespace nbv::sensor
