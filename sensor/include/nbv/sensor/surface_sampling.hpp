#pragma once
/// \file Ground truth for surface coverage (SEMANTICS.md "Simulation and evaluation", Eq. 15): points spread uniformly by area
/// over a mesh.
///
/// Thread-safety: the functions share no state (the seed fixes each sample) and may run in several
/// threads at once.

#include "nbv/sensor/mesh.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace nbv::sensor {

/// Default number of ground-truth points. A normalised model (largest side 0.5 m) has a
/// surface of about half a square metre (the bunny: 0.59 m^2, measured in
/// SurfaceSampling.DefaultCountIsDenseOnTheNormalisedBunny), so 200,000 points are about
/// 1.7 mm apart on average: a disc of the 5 mm registration radius of Eq. 15 holds ~27 of
/// them, and each point stands for ~3 mm^2 of surface.
inline constexpr std::size_t kDefaultGroundTruthPoints = 200000;

/// `count` points drawn uniformly by area on `mesh` (a triangle is picked with probability
/// proportional to its area, then a uniform point in it), from the seeded std::mt19937_64.
/// Same mesh, count and seed: same points. \throws InvalidArgument if the mesh has no
/// area.
std::vector<Eigen::Vector3f> sampleSurface(const TriangleMesh& mesh, std::size_t count,
                                           std::uint64_t seed);

/// Total area of the mesh's triangles [m^2 once normalised].
double surfaceArea(const TriangleMesh& mesh);

}  // namespace nbv::sensor
