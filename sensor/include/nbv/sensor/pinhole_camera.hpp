#pragma once
/// \file The one pinhole camera model of nbv (SPEC §2): pixel -> ray for the depth camera and
/// for the IG ray sets alike.

#include <Eigen/Core>

namespace nbv::sensor {

/// Pinhole intrinsics. Optical frame: z forward, image column u along x, row v along y.
/// Defaults: the paper's camera (752 x 480, about 80 degrees horizontal field of view).
struct PinholeCamera {
  int width = 752;                     ///< pixels
  int height = 480;                    ///< pixels
  double fx = 448.1008985853343;       ///< focal length [pixels]
  double fy = 448.1008985853343;       ///< focal length [pixels]
  double cx = 376.5;                   ///< principal point, column [pixels]
  double cy = 240.5;                   ///< principal point, row [pixels]

  /// Throws std::invalid_argument naming the first bad value.
  void validate() const;

  /// Unit direction, in the camera frame, of the ray through pixel (u, v):
  /// normalise((u - cx) / fx, (v - cy) / fy, 1) (SPEC §2). Thread-safe.
  Eigen::Vector3d rayDirectionCamera(double u, double v) const {
    return Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0).normalized();
  }
};

}  // namespace nbv::sensor
