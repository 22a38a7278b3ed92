#pragma once
/// \file The one pinhole camera model of nbv (SEMANTICS.md "Views and rays"): pixel -> ray for the depth camera and
/// for the IG ray sets alike.

#include <Eigen/Core>

#include <string>
#include <vector>

namespace nbv::sensor {

/// Pinhole intrinsics. Optical frame: z forward, image column u along x, row v along y; a
/// negative focal length flips its axis (as ICL-NUIM's fy = -480: row v along -y).
/// Defaults: the paper's camera (752 x 480, about 80 degrees horizontal field of view).
struct PinholeCamera {
  int width = 752;                     ///< pixels
  int height = 480;                    ///< pixels
  double fx = 448.1008985853343;       ///< focal length [pixels], not 0
  double fy = 448.1008985853343;       ///< focal length [pixels], not 0
  double cx = 376.5;                   ///< principal point, column [pixels]
  double cy = 240.5;                   ///< principal point, row [pixels]

  /// The widest and tallest image [pixels]: 16384 x 16384 is 268 million rays per render.
  static constexpr int kMaxSide = 16384;

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;

  /// Unit direction, in the camera frame, of the ray through pixel (u, v):
  /// normalise((u - cx) / fx, (v - cy) / fy, 1) (SEMANTICS.md "Views and rays"). Thread-safe.
  Eigen::Vector3d rayDirectionCamera(double u, double v) const {
    return Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1.0).normalized();
  }
};

/// Which pixels carry an IG ray (SEMANTICS.md "Views and rays"): every `stride`-th pixel of the central `window`
/// fraction of the image, in each direction, both window edges included.
struct PixelSampling {
  int stride = 1;       ///< pixels between two rays, >= 1
  double window = 1.0;  ///< central fraction of width and height, in (0, 1]
  /// The window of an image with width and height exchanged, clipped to that image and not to
  /// this one: what the released launch file casts (its image sides swapped, its principal
  /// point kept), an off-centre window partly outside the image.
  bool swapped_sides = false;

  /// Every pixel: 752 x 480 = 360,960 rays with the default camera.
  static PixelSampling full() { return {1, 1.0}; }
  /// The released code's setting: stride 10 on the central 50 %: 38 x 25 = 950 rays.
  static PixelSampling released() { return {10, 0.5}; }
  /// The released code's setting as its shipped files cast it: 25 x 38 = 950 rays of columns
  /// 120-360 and rows 188-558 with the default camera.
  static PixelSampling releasedShipped() { return {10, 0.5, true}; }
  /// Throws InvalidArgument naming the bad value.
  void validate() const;
  /// "released", "released-shipped", "full", or a stride N (every N-th pixel of the whole
  /// image), as the command line spells ray sets. \throws InvalidArgument naming the text.
  static PixelSampling fromName(const std::string& name);
  /// The ray sets fromName() knows, for help texts.
  static constexpr const char* kNamesHelp =
      "released (950 rays), released-shipped (the 950 the shipped launch file casts), full (360,960) or a pixel stride";
};

/// One sampled pixel and its ray direction in the camera frame.
struct PixelRay {
  int u = 0;
  int v = 0;
  Eigen::Vector3d direction_camera;
};

/// The IG ray set of one view, in the camera frame, row-major: the same pixel -> ray as the
/// depth camera (PinholeCamera::rayDirectionCamera). \throws InvalidArgument for a bad
/// camera or sampling.
std::vector<PixelRay> pixelRays(const PinholeCamera& camera, const PixelSampling& sampling);

/// Just the unit directions of pixelRays(), in the same order: the input of the IG evaluators.
std::vector<Eigen::Vector3d> rayDirectionsCamera(const PinholeCamera& camera, const PixelSampling& sampling);

}  // namespace nbv::sensor
