#pragma once
// Private to the Python module: the parts of nbv._nbv, one function per area.

#include "nbv/grid/information_gain.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"

#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace nbv::python {

namespace py = pybind11;

/// A mesh in the world frame and the ray-casting scene built from it on first use.
class Mesh {
 public:
  Mesh(sensor::TriangleMesh mesh, const Eigen::Affine3d& T_mesh_file) : mesh_(std::move(mesh)), transform_(T_mesh_file) {}
  const sensor::TriangleMesh& mesh() const { return mesh_; }
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
  mutable std::once_flag built_[2];
  mutable std::unique_ptr<sensor::RayScene> scenes_[2];
};

/// A standard model or a mesh file, placed as the command line places it ("z" or "y" up).
std::shared_ptr<Mesh> loadModel(const std::string& name_or_path, const std::string& up = "z");
/// The visibility named "paper" or "released". \throws InvalidArgument for another name.
grid::Visibility visibilityOf(const std::string& name);
/// A model name or a mesh file's path given as a str or an os.PathLike; none for anything else.
std::optional<std::string> modelNameOrPath(const py::handle& value);

void bindErrors(py::module_& m);
void bindMap(py::module_& m);
void bindSensor(py::module_& m);
void bindInformationGain(py::module_& m);
void bindPlanner(py::module_& m);
void bindExperiment(py::module_& m);

}  // namespace nbv::python
