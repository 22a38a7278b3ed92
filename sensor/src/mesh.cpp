#include "nbv/sensor/mesh.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <mutex>

namespace nbv::sensor {

namespace {

namespace fs = std::filesystem;

/// Errors assimp logs while importing on this thread. Some loaders repair bad input and only
/// log it (the OFF loader clamps out-of-range vertex indices), so a logged error refuses the
/// file.
thread_local std::string assimp_errors;

class ErrorCollector : public Assimp::LogStream {
 public:
  void write(const char* message) override { assimp_errors += message; }
};

/// Attaches the collector to assimp's logger once: to the application's logger if it set
/// one, else to a silent logger of ours (no file, no console).
void listenToAssimpErrors() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (Assimp::DefaultLogger::isNullLogger()) {
      Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);
    }
    Assimp::DefaultLogger::get()->attachStream(new ErrorCollector, Assimp::Logger::Err);
  });
}

/// Appends the triangles of `node` and its children, in world coordinates of the file.
void collect(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, const fs::path& path,
             TriangleMesh& mesh, MeshLoadReport& report) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& source = *scene.mMeshes[node.mMeshes[m]];
    const auto base = static_cast<int>(mesh.vertices.size());
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D p = transform * source.mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        throw MeshFileError(path, "vertex " + std::to_string(v) + " is not finite");
      }
      mesh.vertices.emplace_back(p.x, p.y, p.z);
    }
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
      const aiFace& face = source.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= source.mNumVertices) {
          throw MeshFileError(path, "face " + std::to_string(f) + " uses vertex " +
                                        std::to_string(face.mIndices[k]) + " of " +
                                        std::to_string(source.mNumVertices));
        }
        tri[k] = base + static_cast<int>(face.mIndices[k]);
      }
      const Eigen::Vector3f& a = mesh.vertices[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3f& b = mesh.vertices[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3f& c = mesh.vertices[static_cast<std::size_t>(tri[2])];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || (b - a).cross(c - a).squaredNorm() == 0.0f) {
        ++report.degenerate_dropped;
        continue;
      }
      mesh.triangles.push_back(tri);
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    collect(scene, *node.mChildren[c], transform, path, mesh, report);
  }
}

/// Refuses an OFF file whose header claims more vertices and faces than its bytes can hold
/// (each vertex line takes at least 6 bytes, "0 0 0\n", each face at least 8): assimp's OFF
/// loader allocates whatever the header says, and 60 bytes claiming 10^9 vertices exhaust
/// the memory. Other formats: assimp checks them itself.
void checkOffCounts(const fs::path& path, std::uintmax_t file_size) {
  std::ifstream in(path);
  std::string keyword;
  if (!(in >> keyword) || keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0) return;
  std::string vertices_text, faces_text;
  if (!(in >> vertices_text >> faces_text)) throw MeshFileError(path, "OFF header has no vertex and face counts");
  char* end_v = nullptr;
  char* end_f = nullptr;
  const long double vertices = std::strtold(vertices_text.c_str(), &end_v);
  const long double faces = std::strtold(faces_text.c_str(), &end_f);
  if (*end_v != '\0' || *end_f != '\0' || !(vertices >= 0) || !(faces >= 0)) {
    throw MeshFileError(path, "OFF header counts '" + vertices_text + " " + faces_text + "' are not counts");
  }
  if (6.0L * vertices + 8.0L * faces > static_cast<long double>(file_size)) {
    throw MeshFileError(path, "OFF header claims " + vertices_text + " vertices and " + faces_text +
                                  " faces, more than the file can hold");
  }
}

}  // namespace

TriangleMesh loadMesh(const fs::path& path, MeshLoadReport* report) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw MeshFileError(path, "no such file");
  if (fs::is_directory(status)) throw MeshFileError(path, "is a directory, not a mesh file");
  const std::uintmax_t file_size = fs::file_size(path, ec);
  if (file_size == 0 || ec) throw MeshFileError(path, "file is empty");
  checkOffCounts(path, file_size);

  listenToAssimpErrors();
  assimp_errors.clear();
  Assimp::Importer importer;
  // No post-processing that drops or merges triangles: degenerate ones are counted here.
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_ValidateDataStructure);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw MeshFileError(path, std::string("cannot read mesh: ") + importer.GetErrorString());
  }
  if (!assimp_errors.empty()) {
    std::string message = assimp_errors;
    while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
    throw MeshFileError(path, "malformed mesh: " + message);
  }
  TriangleMesh mesh;
  MeshLoadReport local;
  collect(*scene, *scene->mRootNode, aiMatrix4x4(), path, mesh, local);
  if (mesh.triangles.empty()) throw MeshFileError(path, "mesh has no (non-degenerate) triangles");
  if (report != nullptr) *report = local;
  return mesh;
}

Eigen::AlignedBox3d meshBounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d bounds;
  for (const Eigen::Vector3f& v : mesh.vertices) bounds.extend(v.cast<double>());
  return bounds;
}

Normalization normalizeMesh(TriangleMesh& mesh, double largest_side_m) {
  if (mesh.vertices.empty()) throw std::invalid_argument("cannot normalise an empty mesh");
  const Eigen::AlignedBox3d bounds = meshBounds(mesh);
  const double largest = bounds.sizes().maxCoeff();
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    throw std::invalid_argument("cannot normalise a mesh with no extent");
  }
  // SPEC §5: scale, centre on the z axis, lowest point at z = 0.
  const double scale = largest_side_m / largest;
  const Eigen::Vector3d anchor(bounds.center().x(), bounds.center().y(), bounds.min().z());
  Normalization n;
  n.T_normalized_original = Eigen::Scaling(scale) * Eigen::Translation3d(-anchor);
  for (Eigen::Vector3f& v : mesh.vertices) v = (n.T_normalized_original * v.cast<double>()).cast<float>();
  return n;
}

const std::vector<std::pair<std::string, std::string>>& modelNames() {
  static const std::vector<std::pair<std::string, std::string>> names = {
      {"bunny", "bunny00.off"},
      {"armadillo", "armadillo.off"},
      {"dragon", "ChineseDragon-10kv.off"},
      {"dino", "dino.off"},
      {"head", "head.off"}};
  return names;
}

fs::path resolveModel(const std::string& name_or_path, const fs::path& models_dir) {
  for (const auto& [name, file] : modelNames()) {
    if (name_or_path == name) return models_dir / file;
  }
  return name_or_path;
}

}  // namespace nbv::sensor
