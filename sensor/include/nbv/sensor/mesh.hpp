#pragma once
/// \file Triangle meshes of the objects to reconstruct: loading, checking, and the
/// normalisation of SEMANTICS.md "Simulation and evaluation".

#include "nbv/errors.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace nbv::sensor {

/// An indexed triangle mesh; coordinates in metres once normalised.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> triangles;  ///< vertex indices, counter-clockwise
};

/// What loadMesh() found besides the mesh.
struct MeshLoadReport {
  std::size_t degenerate_dropped = 0;  ///< triangles with repeated vertices or zero area
};

/// Loads every triangle of a mesh file. OFF (COFF too), PLY, OBJ and STL (binary or ASCII) are
/// read by nbv's own readers, which check counts against the file size before allocating and
/// name the line of any error; other extensions go through assimp (node transforms applied).
/// Polygons become triangle fans; degenerate triangles are dropped and counted.
/// \throws MeshFileError for a missing or unreadable file, no triangles, non-finite vertices
/// or out-of-range indices.
TriangleMesh loadMesh(const std::filesystem::path& path, MeshLoadReport* report = nullptr);

/// The placement of an object (SEMANTICS.md "Simulation and evaluation"): uniformly scaled so that the largest side of its
/// bounding box is `largest_side_m`, centred on the z axis, lowest point at z = 0.
struct Normalization {
  Eigen::Affine3d T_normalized_original = Eigen::Affine3d::Identity();  ///< original -> normalised
};

/// Normalises `mesh` in place and returns the transform, so results can be mapped back.
/// \throws InvalidArgument for an empty mesh or one with no extent.
Normalization normalizeMesh(TriangleMesh& mesh, double largest_side_m = 0.5);

/// Axis-aligned bounds of the mesh's vertices.
Eigen::AlignedBox3d meshBounds(const TriangleMesh& mesh);

/// The file of a model: a short name (bunny, armadillo, dragon, dino, head) resolves to its
/// CGAL file in `models_dir`; anything else is taken as a path.
/// \throws MeshFileError if the file does not exist: for a short name, saying that the models
/// are not extracted yet; for anything else, listing the short names.
std::filesystem::path resolveModel(const std::string& name_or_path,
                                   const std::filesystem::path& models_dir);

/// The short model names and their files, in the order above.
const std::vector<std::pair<std::string, std::string>>& modelNames();

}  // namespace nbv::sensor
