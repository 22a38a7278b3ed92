#include "nbv/sensor/mesh.hpp"

#include "file_bytes.hpp"
#include "mesh_formats.hpp"

#include "nbv/errors.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cctype>
#include <cmath>
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
void collect(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, detail::MeshBuilder& builder) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& source = *scene.mMeshes[node.mMeshes[m]];
    const std::uint64_t base = builder.vertexCount();
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D p = transform * source.mVertices[v];
      builder.addVertex(p.x, p.y, p.z, "mesh " + std::to_string(m));
    }
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
      const aiFace& face = source.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      std::uint64_t tri[3];
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= source.mNumVertices) {
          throw MeshFileError(builder.path(), "face " + std::to_string(f) + " uses vertex " +
                                                  std::to_string(face.mIndices[k]) + " of " +
                                                  std::to_string(source.mNumVertices));
        }
        tri[k] = base + face.mIndices[k];
      }
      builder.addPolygon(tri, 3, "face " + std::to_string(f));
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) collect(scene, *node.mChildren[c], transform, builder);
}

/// Formats other than the four nbv reads itself go through assimp.
TriangleMesh loadThroughAssimp(const fs::path& path, MeshLoadReport& report) {
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
  detail::MeshBuilder builder(path, report);
  collect(*scene, *scene->mRootNode, aiMatrix4x4(), builder);
  return builder.finish();
}

std::string lowercaseExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

TriangleMesh loadMesh(const fs::path& path, MeshLoadReport* report) {
  MeshLoadReport local;
  const std::string ext = lowercaseExtension(path);
  using Reader = TriangleMesh (*)(const std::string&, const fs::path&, MeshLoadReport&);
  const Reader reader = ext == ".off"   ? detail::readOff
                        : ext == ".obj" ? detail::readObj
                        : ext == ".stl" ? detail::readStl
                        : ext == ".ply" ? detail::readPlyMesh
                                        : nullptr;
  TriangleMesh mesh;
  if (reader != nullptr) {
    mesh = reader(detail::readWholeFile<MeshFileError>(path, "a mesh file"), path, local);
  } else {
    detail::requireInputFile<MeshFileError>(path, "a mesh file");  // the same refusals first
    mesh = loadThroughAssimp(path, local);
  }
  if (report != nullptr) *report = local;
  return mesh;
}

Eigen::AlignedBox3d meshBounds(const TriangleMesh& mesh) {
  Eigen::AlignedBox3d bounds;
  for (const Eigen::Vector3f& v : mesh.vertices) bounds.extend(v.cast<double>());
  return bounds;
}

TriangleMesh boxMesh(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

void appendMesh(TriangleMesh& mesh, const TriangleMesh& part) {
  const auto shift = static_cast<int>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (const Eigen::Vector3i& t : part.triangles) mesh.triangles.push_back(t + Eigen::Vector3i::Constant(shift));
}

UpAxis upAxisFromName(const std::string& name) {
  if (name == "z") return UpAxis::Z;
  if (name == "y") return UpAxis::Y;
  throw InvalidArgument("up axis '" + name + "' is not 'z', 'y' or 'auto'");
}

Normalization normalizeMesh(TriangleMesh& mesh, const Placement& placement) {
  if (mesh.vertices.empty()) throw InvalidArgument("cannot normalise an empty mesh");
  // A y-up file turns +90 degrees about x first: (x, y, z) -> (x, -z, y).
  const bool turn = placement.up == UpAxis::Y;
  const Eigen::Affine3d upright(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitX()));
  Eigen::AlignedBox3d bounds;
  for (const Eigen::Vector3f& v : mesh.vertices) bounds.extend(turn ? upright * v.cast<double>() : v.cast<double>());
  const double largest = bounds.sizes().maxCoeff();
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    throw InvalidArgument("cannot normalise a mesh with no extent");
  }
  if (!(placement.largest_side_m > 0.0) || !std::isfinite(placement.largest_side_m)) {
    throw InvalidArgument("largest side " + numberText(placement.largest_side_m) + " m must be positive");
  }
  // SEMANTICS.md "Simulation and evaluation": scale, centre on the z axis, lowest point at z = 0.
  const double scale = placement.largest_side_m / largest;
  const Eigen::Vector3d anchor(bounds.center().x(), bounds.center().y(), bounds.min().z());
  Normalization n;
  n.T_normalized_original = Eigen::Scaling(scale) * Eigen::Translation3d(-anchor);
  if (turn) n.T_normalized_original = n.T_normalized_original * upright;
  for (Eigen::Vector3f& v : mesh.vertices) v = (n.T_normalized_original * v.cast<double>()).cast<float>();
  return n;
}

UpAxis upAxisFor(const std::string& name_or_path, const std::string& up) {
  if (up != "auto") return upAxisFromName(up);
  for (const StandardModel& model : standardModels()) {
    if (model.name == name_or_path) return model.stored_up;
  }
  return UpAxis::Z;
}

}  // namespace nbv::sensor
