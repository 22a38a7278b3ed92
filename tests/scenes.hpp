#pragma once
// Analytic scenes for the tests: ideal scans of a sphere and a box, computed in closed form.

#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <optional>
#include <vector>

namespace nbv::test {

/// Axis-aligned box [lo, hi] as 12 triangles (the library's).
using sensor::boxMesh;

/// Sphere as a UV mesh with `n` rings; its largest chord error is r (1 - cos(pi / n)).
inline sensor::TriangleMesh sphereMesh(const Eigen::Vector3f& centre, float r, int n) {
  sensor::TriangleMesh m;
  for (int i = 0; i <= n; ++i) {
    const double theta = M_PI * i / n;
    for (int j = 0; j < 2 * n; ++j) {
      const double phi = M_PI * j / n;
      m.vertices.push_back(centre + r * Eigen::Vector3f(static_cast<float>(std::sin(theta) * std::cos(phi)),
                                                        static_cast<float>(std::sin(theta) * std::sin(phi)),
                                                        static_cast<float>(std::cos(theta))));
    }
  }
  auto at = [n](int i, int j) { return i * 2 * n + (j % (2 * n)); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < 2 * n; ++j) {
      if (i > 0) m.triangles.emplace_back(at(i, j), at(i + 1, j), at(i, j + 1));
      if (i < n - 1) m.triangles.emplace_back(at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
    }
  }
  return m;
}

/// The camera at `position` looking at `target`, with the roll of SEMANTICS.md "The planner".
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  return planner::lookAt(position, target).T_world_camera;
}

/// Distance along a unit ray to a surface, or nothing.
using Intersector = std::optional<double> (*)(const Eigen::Vector3d& origin,
                                              const Eigen::Vector3d& direction, const void* shape);

struct Sphere {
  Eigen::Vector3d centre;
  double radius;
  /// Nearest positive hit distance (from inside: the exit).
  std::optional<double> intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    const Eigen::Vector3d oc = o - centre;
    const double b = oc.dot(d);
    const double c = oc.squaredNorm() - radius * radius;
    const double disc = b * b - c;
    if (disc < 0.0) return std::nullopt;
    const double s = std::sqrt(disc);
    if (-b - s > 0.0) return -b - s;
    if (-b + s > 0.0) return -b + s;
    return std::nullopt;
  }
};

struct Box {
  Eigen::Vector3d min, max;
  std::optional<double> intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double t0 = 0.0, t1 = 1e30;
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      if (o[a] < min[a] || o[a] > max[a]) inside = false;
      if (d[a] == 0.0) {
        if (o[a] < min[a] || o[a] > max[a]) return std::nullopt;
        continue;
      }
      double ta = (min[a] - o[a]) / d[a], tb = (max[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (t0 > t1) return std::nullopt;
    }
    return inside ? t1 : t0;
  }
};

/// Ideal scan of `shape` every `stride`-th pixel: one world point per pixel whose ray hits.
template <class Shape>
std::vector<Eigen::Vector3f> idealScan(const Shape& shape, const Eigen::Isometry3d& T_world_camera,
                                       int stride = 1,
                                       const sensor::PinholeCamera& camera = sensor::PinholeCamera{}) {
  std::vector<Eigen::Vector3f> points;
  const Eigen::Vector3d origin = T_world_camera.translation();
  for (int v = 0; v < camera.height; v += stride) {
    for (int u = 0; u < camera.width; u += stride) {
      const Eigen::Vector3d d = T_world_camera.linear() * camera.rayDirectionCamera(u, v);
      if (const auto t = shape.intersect(origin, d)) {
        points.push_back((origin + *t * d).template cast<float>());
      }
    }
  }
  return points;
}

}  // namespace nbv::test
