#pragma once
/// \file nbv's own readers of the mesh formats it documents (OFF/COFF, PLY, OBJ, STL), and the
/// one place where faces become triangles (private header of nbv::sensor).

#include "nbv/sensor/mesh.hpp"

#include <cstdint>
#include <filesystem>
#include <string>

namespace nbv::sensor::detail {

/// Collects vertices and polygons into a TriangleMesh: checks every vertex is finite and every
/// index in range, fans polygons into triangles, drops degenerate ones and counts them.
class MeshBuilder {
 public:
  MeshBuilder(const std::filesystem::path& path, MeshLoadReport& report) : path_(path), report_(report) {}

  /// \throws MeshFileError naming `where` (a line, a face) if the vertex is not finite.
  void addVertex(double x, double y, double z, const std::string& where);
  /// Adds the polygon of `count` vertex indices (0-based) as a fan of triangles.
  /// \throws MeshFileError naming `where` for fewer than 3 vertices or an index out of range.
  void addPolygon(const std::uint64_t* indices, std::size_t count, const std::string& where);
  std::size_t vertexCount() const { return mesh_.vertices.size(); }
  const std::filesystem::path& path() const { return path_; }
  /// \throws MeshFileError if no (non-degenerate) triangle was added.
  TriangleMesh finish();

 private:
  const std::filesystem::path& path_;
  MeshLoadReport& report_;
  TriangleMesh mesh_;
};

/// Readers of a whole file held in `bytes`; `path` only names the file in errors.
/// \throws MeshFileError naming the line (or byte) and the problem.
TriangleMesh readOff(const std::string& bytes, const std::filesystem::path& path, MeshLoadReport& report);
TriangleMesh readObj(const std::string& bytes, const std::filesystem::path& path, MeshLoadReport& report);
TriangleMesh readStl(const std::string& bytes, const std::filesystem::path& path, MeshLoadReport& report);
TriangleMesh readPlyMesh(const std::string& bytes, const std::filesystem::path& path, MeshLoadReport& report);

}  // namespace nbv::sensor::detail
