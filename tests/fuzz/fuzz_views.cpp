// View files: read or refused with ViewFileError; views read are finite with unit rotations.
#include "fuzz_input_file.hpp"

#include "nbv/planner/viewspace.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nbv::fuzz::writeInput(data, size, ".txt");
  try {
    for (const nbv::planner::View& view : nbv::planner::loadViews(path)) {
      nbv::fuzz::check(view.T_world_camera.matrix().allFinite(), "finite poses");
      const Eigen::Matrix3d R = view.T_world_camera.linear();
      nbv::fuzz::check((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9, "rotations");
    }
  } catch (const nbv::ViewFileError&) {
  }
  return 0;
}
