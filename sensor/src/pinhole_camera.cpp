#include "nbv/sensor/pinhole_camera.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace nbv::sensor {

void PinholeCamera::validate() const {
  auto require = [](bool ok, const char* name, const std::string& value, const std::string& rule) {
    if (!ok) throw InvalidArgument("invalid camera: " + std::string(name) + " = " + value + " (" + rule + ")");
  };
  const std::string sides = "1 to " + std::to_string(kMaxSide) + " pixels";
  require(width > 0 && width <= kMaxSide, "width", std::to_string(width), sides);
  require(height > 0 && height <= kMaxSide, "height", std::to_string(height), sides);
  // A negative focal length flips its image axis (SEMANTICS.md "Views and rays"); zero has no ray.
  require(std::isfinite(fx) && fx != 0.0, "fx", numberText(fx), "finite and not 0");
  require(std::isfinite(fy) && fy != 0.0, "fy", numberText(fy), "finite and not 0");
  require(std::isfinite(cx), "cx", numberText(cx), "finite");
  require(std::isfinite(cy), "cy", numberText(cy), "finite");
}

void PixelSampling::validate() const {
  if (stride < 1) throw InvalidArgument("ray stride must be >= 1, got " + std::to_string(stride));
  if (!(window > 0.0 && window <= 1.0)) {
    throw InvalidArgument("ray window must be in (0, 1], got " + numberText(window));
  }
}

PixelSampling PixelSampling::fromName(const std::string& name) {
  if (name == "released") return released();
  if (name == "released-shipped") return releasedShipped();
  if (name == "full") return full();
  std::size_t used = 0;
  int stride = 0;
  try {
    stride = std::stoi(name, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != name.size() || stride < 1) {
    throw InvalidArgument("ray set '" + name + "' is not 'released', 'released-shipped', 'full' or a stride >= 1");
  }
  return {stride, 1.0};
}

std::vector<Eigen::Vector3d> rayDirectionsCamera(const PinholeCamera& camera, const PixelSampling& sampling) {
  std::vector<Eigen::Vector3d> directions;
  for (const PixelRay& ray : pixelRays(camera, sampling)) directions.push_back(ray.direction_camera);
  return directions;
}

std::vector<PixelRay> pixelRays(const PinholeCamera& camera, const PixelSampling& sampling) {
  camera.validate();
  sampling.validate();
  // Central window, both edges included, clipped to the image (swapped_sides: to the image of
  // exchanged sides, whose window it is).
  auto range = [&](int size) {
    const int first = static_cast<int>(std::floor(size * (1.0 - sampling.window) / 2.0));
    const int last = std::min(size - 1, static_cast<int>(std::floor(size * (1.0 + sampling.window) / 2.0)));
    return std::pair<int, int>(first, last);
  };
  const auto [u_first, u_last] = range(sampling.swapped_sides ? camera.height : camera.width);
  const auto [v_first, v_last] = range(sampling.swapped_sides ? camera.width : camera.height);
  std::vector<PixelRay> rays;
  rays.reserve(static_cast<std::size_t>((u_last - u_first) / sampling.stride + 1) *
               static_cast<std::size_t>((v_last - v_first) / sampling.stride + 1));
  for (int v = v_first; v <= v_last; v += sampling.stride) {
    for (int u = u_first; u <= u_last; u += sampling.stride) {
      rays.push_back({u, v, camera.rayDirectionCamera(u, v)});
    }
  }
  return rays;
}

}  // namespace nbv::sensor
