#pragma once
/// \file Triangle meshes of the objects to reconstruct: loading, checking, and the
/// normalisation of SEMANTICS.md "Simulation and evaluation".
///
/// Thread-safety: loading shares no state (an Assimp importer per call) and may run in several
/// threads at once; a TriangleMesh is a plain value.

#include "nbv/errors.hpp"
#include "nbv/sensor/models.hpp"

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

/// "z" or "y". \throws InvalidArgument for another name.
UpAxis upAxisFromName(const std::string& name);

/// How an object is placed in the world (SEMANTICS.md "Simulation and evaluation").
struct Placement {
  UpAxis up = UpAxis::Z;         ///< the file's up axis
  double largest_side_m = 0.5;   ///< the largest side of the bounding box after scaling
};

/// The placement of an object: turned upright if stored y-up, uniformly scaled so that the
/// largest side of its bounding box is `largest_side_m`, centred on the z axis, lowest point at
/// z = 0.
struct Normalization {
  Eigen::Affine3d T_normalized_original = Eigen::Affine3d::Identity();  ///< original -> normalised
};

/// Places `mesh` in place as `placement` says and returns the transform, so results can be
/// mapped back. \throws InvalidArgument for an empty mesh or one with no extent.
Normalization normalizeMesh(TriangleMesh& mesh, const Placement& placement = Placement{});

/// Axis-aligned bounds of the mesh's vertices.
Eigen::AlignedBox3d meshBounds(const TriangleMesh& mesh);

/// The axis-aligned box [lo, hi] [m] as 12 triangles, faces outward: walls, floors and
/// furniture of the synthetic scenes (SEMANTICS.md "Real-scale workloads").
TriangleMesh boxMesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi);

/// Adds the vertices and triangles of `part` to `mesh` (its indices shifted): several objects
/// in one scene.
void appendMesh(TriangleMesh& mesh, const TriangleMesh& part);

/// The up axis that `up` ("z", "y" or "auto") names for a model: "auto" is a standard model's
/// stored up axis, so that it stands upright, and z for a mesh file.
/// \throws InvalidArgument for another name.
UpAxis upAxisFor(const std::string& name_or_path, const std::string& up);

}  // namespace nbv::sensor
