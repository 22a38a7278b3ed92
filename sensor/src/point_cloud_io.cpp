#include "nbv/sensor/point_cloud_io.hpp"

#include "file_bytes.hpp"
#include "ply_reader.hpp"

#include <bit>
#include <fstream>

namespace nbv::sensor {

namespace fs = std::filesystem;

std::vector<Eigen::Vector3f> readPlyCloud(const fs::path& path) {
  const std::string bytes = detail::readWholeFile<CloudFileError>(path, "a PLY file");
  try {
    return detail::parsePly(bytes, /*with_faces=*/false).vertices;
  } catch (const detail::PlyProblem& problem) {
    throw CloudFileError(path, problem.what());
  }
}

void writePlyCloud(const fs::path& path, const std::vector<Eigen::Vector3f>& points) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw CloudFileError(path, "cannot open for writing");
  out << "ply\nformat binary_little_endian 1.0\ncomment written by nbv\nelement vertex "
      << points.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  static_assert(std::endian::native == std::endian::little, "PLY writer assumes little endian");
  for (const Eigen::Vector3f& p : points) {
    out.write(reinterpret_cast<const char*>(p.data()), 3 * sizeof(float));
  }
  out.flush();
  if (!out) throw CloudFileError(path, "write failed (disk full?)");
}

}  // namespace nbv::sensor
