#include "nbv/planner/workloads.hpp"

#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"

#include "nbv/errors.hpp"


namespace nbv::planner {

std::vector<std::string> workloadNames() { return {"bunny-3"}; }

Workload makeWorkload(const std::string& name, const std::vector<std::filesystem::path>& models) {
  if (name != "bunny-3") {
    throw InvalidArgument("unknown workload '" + name + "' (known: bunny-3)");
  }
  sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel("bunny", models));
  sensor::normalizeMesh(mesh);  // SEMANTICS.md "Simulation and evaluation"
  const sensor::RayScene scene(mesh);
  const sensor::DepthCamera camera;
  Workload workload{name, grid::OccupancyMap(grid::MapConfig{}), dome48()};
  for (const std::size_t index : {0u, 16u, 33u}) {
    const Eigen::Isometry3d& T_world_camera = workload.candidates[index].T_world_camera;
    workload.map.integrate(camera.render(scene, T_world_camera).points_world,
                           T_world_camera.translation().cast<float>());
  }
  return workload;
}

}  // namespace nbv::planner
