// Meshes in the four formats nbv reads itself (the first byte picks OFF, OBJ, STL or PLY):
// read or refused with MeshFileError; a mesh read has finite vertices and in-range triangles.
#include "fuzz_input_file.hpp"

#include "nbv/sensor/mesh.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".off", ".obj", ".stl", ".ply"};
  const auto path = nbv::fuzz::writeInput(data + 1, size - 1, kExtensions[data[0] % 4]);
  try {
    const nbv::sensor::TriangleMesh mesh = nbv::sensor::loadMesh(path);
    nbv::fuzz::check(!mesh.triangles.empty(), "a mesh read has triangles");
    for (const Eigen::Vector3f& v : mesh.vertices) nbv::fuzz::check(v.allFinite(), "finite vertices");
    for (const Eigen::Vector3i& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        nbv::fuzz::check(t[k] >= 0 && static_cast<std::size_t>(t[k]) < mesh.vertices.size(), "indices in range");
      }
    }
  } catch (const nbv::MeshFileError&) {
  }
  return 0;
}
