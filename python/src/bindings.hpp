#pragma once
// Private to the Python module: the parts of nbv._nbv, one function per area.

#include "nbv/ig/evaluator.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"

#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>

namespace nbv::python {

namespace py = pybind11;

/// A mesh in the world frame and the ray-casting scene built from it on first use.
class Mesh {
 public:
  Mesh(sensor::TriangleMesh mesh, const Eigen::Affine3d& T_mesh_file, std::string source = {}, std::string up = "z")
      : mesh_(std::move(mesh)), transform_(T_mesh_file), source_(std::move(source)), up_(std::move(up)) {}
  const sensor::TriangleMesh& mesh() const { return mesh_; }
  /// What it was loaded from (a standard name or a file's absolute path), empty for arrays.
  const std::string& source() const { return source_; }
  /// The up axis it was placed with ("z", "y" or "auto"), with source().
  const std::string& up() const { return up_; }
  /// Maps the mesh file's coordinates to the mesh's (the normalisation of load_mesh()).
  const Eigen::Affine3d& transform() const { return transform_; }
  /// The Embree scene, alone or on the ground plane, built once each; thread-safe.
  const sensor::RayScene& scene(bool ground_plane) const {
    const int k = ground_plane ? 1 : 0;
    std::call_once(built_[k], [&] { scenes_[k] = std::make_unique<sensor::RayScene>(mesh_, sensor::SceneOptions{ground_plane}); });
    return *scenes_[k];
  }

 private:
  sensor::TriangleMesh mesh_;
  Eigen::Affine3d transform_;
  std::string source_;
  std::string up_;
  mutable std::once_flag built_[2];
  mutable std::unique_ptr<sensor::RayScene> scenes_[2];
};

/// A standard model or a mesh file, placed as the command line places it ("z" or "y" up); the
/// last few loaded are kept, so that a name given call after call loads once.
std::shared_ptr<Mesh> loadModel(const std::string& name_or_path, const std::string& up = "z");
/// A model argument as the Python layer gives it: a standard name or a mesh file's path, or an
/// nbv.Mesh.
using ModelGiven = std::variant<std::string, std::shared_ptr<Mesh>>;
/// The mesh of a model argument: an nbv.Mesh as it is, a name or path loaded with `up`.
std::shared_ptr<Mesh> meshOf(const ModelGiven& model, const std::string& up);
/// The visibility named "paper" or "released". \throws InvalidArgument for another name.
ig::Visibility visibilityOf(const std::string& name);
/// The voxels of IgEvaluator::visibleVoxels() as Decider.visible_voxels() returns them: index
/// (K, 3) int32, centres (K, 3) float64 [m], visibility (K,) float64, rays (K,) uint32.
py::dict visibleVoxelsDict(const grid::OccupancyMap& map, const std::vector<ig::VisibleVoxel>& voxels);

void bindErrors(py::module_& m);
void bindMap(py::module_& m);
void bindSensor(py::module_& m);
void bindInformationGain(py::module_& m);
void bindPlanner(py::module_& m);
void bindExperiment(py::module_& m);

}  // namespace nbv::python
