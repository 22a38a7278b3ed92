#include "nbv/sensor/pinhole_camera.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace nbv::sensor {

void PinholeCamera::validate() const {
  auto require = [](bool ok, const char* name, double value) {
    if (!ok) {
      std::ostringstream out;
      out << "invalid camera: " << name << " = " << value;
      throw std::invalid_argument(out.str());
    }
  };
  require(width > 0, "width", width);
  require(height > 0, "height", height);
  require(std::isfinite(fx) && fx > 0.0, "fx", fx);
  require(std::isfinite(fy) && fy > 0.0, "fy", fy);
  require(std::isfinite(cx), "cx", cx);
  require(std::isfinite(cy), "cy", cy);
}

}  // namespace nbv::sensor
