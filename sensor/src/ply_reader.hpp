#pragma once
/// \file The one PLY parser of nbv::sensor, shared by point clouds and meshes (private header).

#include <Eigen/Core>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace nbv::sensor::detail {

/// What is wrong with a PLY file, without its path: callers rethrow it as their typed error.
class PlyProblem : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The vertices of a PLY file and, when asked for, its faces as polygons.
struct PlyData {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::uint32_t> polygon_sizes;    ///< vertices of each face
  std::vector<std::uint64_t> polygon_indices;  ///< all faces' vertex indices, in order (not range-checked)
};

/// Parses a whole PLY file (ascii, binary little or big endian) held in `bytes`: x, y, z of any
/// scalar type from the first `vertex` element, and with `with_faces` the `vertex_indices` (or
/// `vertex_index`) lists of the `face` element. Counts the bytes cannot hold are refused
/// before anything is allocated. Non-finite coordinates are kept.
/// \throws PlyProblem naming the line (ASCII) or byte (binary) and the problem.
PlyData parsePly(const std::string& bytes, bool with_faces);

}  // namespace nbv::sensor::detail
