// Scores the 48 dome views of a one-point map through the installed headers, which use C++20
// (std::span), and catches a documented error by its nbv type.
#include <nbv/errors.hpp>
#include <nbv/ig/evaluator.hpp>
#include <nbv/planner/viewspace.hpp>
#include <nbv/sensor/pinhole_camera.hpp>

#include <cstdio>
#include <span>
#include <vector>

int main() {
  nbv::grid::OccupancyMap map;
  map.integrate({Eigen::Vector3f(0.0f, 0.0f, 0.15f)}, Eigen::Vector3f(0.6f, 0.0f, 0.15f));
  std::vector<Eigen::Isometry3d> views;
  for (const nbv::planner::View& view : nbv::planner::dome48()) views.push_back(view.T_world_camera);
  const auto rays = nbv::sensor::rayDirectionsCamera(nbv::sensor::PinholeCamera{}, nbv::sensor::PixelSampling::released());
  nbv::ig::IgEvaluator evaluator;
  evaluator.refresh(map);
  const nbv::ig::IgTable table = evaluator.evaluate(views, rays);
  try {
    evaluator.evaluate(views, {});
    return 1;
  } catch (const nbv::InvalidArgument&) {
  }
  std::printf("%zu views, %llu rays, oa of view 0: %.6f\n", table.views(),
              static_cast<unsigned long long>(table.rays), table.value(0, 1));
  return table.views() == 48 && table.rays == 48 * 950 ? 0 : 1;
}
