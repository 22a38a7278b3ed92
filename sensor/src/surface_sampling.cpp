#include "nbv/sensor/surface_sampling.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace nbv::sensor {

namespace {

double triangleArea(const TriangleMesh& mesh, const Eigen::Vector3i& t) {
  const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
  const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>();
  const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>();
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

double surfaceArea(const TriangleMesh& mesh) {
  double area = 0.0;
  for (const Eigen::Vector3i& t : mesh.triangles) area += triangleArea(mesh, t);
  return area;
}

std::vector<Eigen::Vector3f> sampleSurface(const TriangleMesh& mesh, std::size_t count,
                                           std::uint64_t seed) {
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    total += triangleArea(mesh, mesh.triangles[i]);
    cumulative[i] = total;
  }
  if (!(total > 0.0)) throw InvalidArgument("cannot sample a mesh with no surface area");

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::Vector3f> points;
  points.reserve(count);
  for (std::size_t n = 0; n < count; ++n) {
    // Triangle by area, then a uniform point in it (the square-root warp of barycentrics).
    const double pick = unit(rng) * total;
    const auto it = std::upper_bound(cumulative.begin(), cumulative.end(), pick);
    const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - cumulative.begin()), cumulative.size() - 1);
    const Eigen::Vector3i& t = mesh.triangles[i];
    const double r1 = std::sqrt(unit(rng));
    const double r2 = unit(rng);
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>();
    const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>();
    points.push_back(((1.0 - r1) * a + r1 * (1.0 - r2) * b + r1 * r2 * c).cast<float>());
  }
  return points;
}

}  // namespace nbv::sensor
