#pragma once
/// \file The ideal depth camera of SEMANTICS.md "Views and rays", "Simulation and evaluation": ray casting against a triangle mesh (Embree).

#include "nbv/errors.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <Eigen/Geometry>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

namespace nbv::sensor {

/// What a scene holds besides the object (SEMANTICS.md "Scene conditions").
struct SceneOptions {
  /// The plane z = 0 (the placed object's lowest point) inside a square of 2 x this [m].
  bool ground_plane = false;
  double ground_half_extent_m = 50.0;
};

/// Which surface a ray met.
enum class Surface : std::uint8_t { Object, Ground };

/// Where a ray met a surface: the distance along the unit ray [m] and which surface.
struct RayHit {
  float distance_m = 0.0f;
  Surface surface = Surface::Object;
};

/// A triangle mesh, and the ground plane if asked for, prepared for ray casting. Immutable once
/// built; queries are thread-safe.
class RayScene {
 public:
  /// \throws SceneError if Embree cannot build the scene; InvalidArgument for a mesh
  /// with no triangles or indices out of range, or a ground extent that is not positive.
  explicit RayScene(const TriangleMesh& mesh, const SceneOptions& options = SceneOptions{});
  ~RayScene();
  RayScene(RayScene&&) noexcept;
  RayScene& operator=(RayScene&&) noexcept;
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  /// The nearest surface along the unit ray origin + t * direction with 0 < t <= max_distance_m,
  /// if any.
  std::optional<RayHit> intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
                                  float max_distance_m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One rendered view.
struct DepthScan {
  int width = 0;
  int height = 0;
  /// Per pixel, row-major: depth along the optical axis [m], 0 where no surface was hit.
  std::vector<float> depth_m;
  /// World point of every pixel that hit, in row-major pixel order.
  std::vector<Eigen::Vector3f> points_world;
  /// The surface of each point of points_world: only object points cover the object.
  std::vector<Surface> surfaces;
};

/// Depth noise of the simulated camera. Default: none (the ideal camera of the paper).
struct DepthNoise {
  enum class Kind {
    None,           ///< exact depths
    AxialGaussian,  ///< depth z + N(0, sigma(z)^2) with sigma(z) = a + b z^2, along the pixel's ray
  };
  Kind kind = Kind::None;
  double a_m = 0.0;          ///< sigma at zero depth [m]
  double b_per_m = 0.0;      ///< growth of sigma with depth squared [1/m]
  std::uint64_t seed = 0;    ///< same seed, pose and scene: same noisy scan
};

/// Pixels that return nothing, as in a real depth sensor's frames (dark or specular surfaces,
/// edges): each pixel dropped with probability `fraction`, and `blocks` squares of
/// `block_size` pixels per side dropped whole, inside the image where they fit, at places drawn
/// from `seed`. Default: none.
struct DepthHoles {
  double fraction = 0.0;       ///< in [0, 1]
  int blocks = 0;              ///< squares per frame, >= 0
  int block_size = 40;         ///< pixels per side, >= 1
  std::uint64_t seed = 0;      ///< same seed: same holes
};

/// Settings of the simulated camera; defaults as SEMANTICS.md "Views and rays", "Simulation and evaluation".
struct DepthCameraConfig {
  PinholeCamera camera;
  double max_range_m = 1.5;      ///< surfaces farther along the ray are not seen
  int tile_size = 32;            ///< pixels per side of one TBB task
  bool serial = false;           ///< render on the calling thread only
  DepthNoise noise;              ///< none by default
  DepthHoles holes;              ///< none by default
};

/// The ideal depth camera: one exact ray per pixel, through the pinhole model of PinholeCamera.
class DepthCamera {
 public:
  /// \throws InvalidArgument for invalid intrinsics, range or tile size.
  explicit DepthCamera(const DepthCameraConfig& config = DepthCameraConfig{});
  const DepthCameraConfig& config() const { return config_; }

  /// Renders `scene` from `T_world_camera` (optical frame: z forward, x along image columns,
  /// y along rows). Deterministic whatever the thread count. Thread-safe.
  /// \throws InvalidArgument if the pose is not finite or its rotation not orthonormal.
  DepthScan render(const RayScene& scene, const Eigen::Isometry3d& T_world_camera) const;

 private:
  DepthCameraConfig config_;
};

}  // namespace nbv::sensor
