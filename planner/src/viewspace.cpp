#include "nbv/planner/viewspace.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

namespace nbv::planner {

View lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = target - position;
  if (!forward.allFinite() || forward.norm() < 1e-12) {
    throw InvalidArgument("lookAt: position and target coincide or are not finite");
  }
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d down(0.0, 0.0, -1.0);
  const Eigen::Vector3d x_unnormalised = down - down.dot(z) * z;  // down, perpendicular to z
  if (x_unnormalised.norm() < 1e-9) {
    throw InvalidArgument("lookAt: a view straight up or down has no defined roll");
  }
  View view;
  Eigen::Matrix3d R;
  R.col(0) = x_unnormalised.normalized();
  R.col(2) = z;
  R.col(1) = z.cross(R.col(0));
  view.T_world_camera.linear() = R;
  view.T_world_camera.translation() = position;
  return view;
}

std::vector<View> fibonacciSphere(std::size_t count, double radius_m, const Eigen::Vector3d& target) {
  if (count == 0 || count > kMaxFibonacciViews) {
    throw InvalidArgument("fibonacciSphere: " + std::to_string(count) + " views; expected 1 to " +
                          std::to_string(kMaxFibonacciViews));
  }
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    throw InvalidArgument("fibonacciSphere: radius " + numberText(radius_m) + " m must be positive");
  }
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<View> views;
  views.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(count);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double a = golden_angle * static_cast<double>(i);
    views.push_back(lookAt(target + radius_m * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), z), target));
  }
  return views;
}

std::vector<View> dome48() {
  constexpr double kRadius = 0.6;
  constexpr double kStep = M_PI / 8.0;  // 22.5 degrees
  const Eigen::Vector3d low_target(0.0, 0.0, 0.15), high_target(0.0, 0.0, 0.35);
  std::vector<View> views;
  views.reserve(48);
  for (int i = 0; i < 16; ++i) {  // ring 1
    const double a = kStep * i;
    views.push_back(lookAt({kRadius * std::cos(a), kRadius * std::sin(a), 0.15}, low_target));
  }
  const double ring3_radius = kRadius * std::cos(M_PI / 4.0);
  const double ring3_height = 0.35 + kRadius * std::sin(M_PI / 4.0);
  for (int j = 0; j < 16; ++j) {  // rings 2 and 3, alternating
    const double a = kStep * j;
    views.push_back(lookAt({kRadius * std::cos(a), kRadius * std::sin(a), 0.35}, high_target));
    views.push_back(lookAt({ring3_radius * std::cos(a), ring3_radius * std::sin(a), ring3_height}, high_target));
  }
  return views;
}

Eigen::Quaterniond canonicalQuaternion(const View& view) {
  Eigen::Quaterniond q(view.T_world_camera.linear());
  q.normalize();
  const double parts[4] = {q.w(), q.z(), q.y(), q.x()};
  for (const double part : parts) {
    if (std::fabs(part) > 1e-12) {
      if (part < 0.0) q.coeffs() = -q.coeffs();
      break;
    }
  }
  return q;
}

std::vector<View> viewsAbove(const std::vector<View>& views, double min_z) {
  std::vector<View> kept;
  std::copy_if(views.begin(), views.end(), std::back_inserter(kept),
               [min_z](const View& v) { return v.T_world_camera.translation().z() >= min_z; });
  return kept;
}

std::vector<View> loadViews(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw ViewFileError(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) throw ViewFileError(path, "is a directory, not a view file");
  std::ifstream in(path);
  if (!in) throw ViewFileError(path, "cannot open for reading");
  std::string line;
  int line_number = 0;
  auto next_line = [&]() -> bool {
    while (std::getline(in, line)) {
      ++line_number;
      if (line.find_first_not_of(" \t\r") != std::string::npos) return true;
    }
    return false;
  };
  if (!next_line()) throw ViewFileError(path, "file is empty");
  long long count = -1;
  {
    std::istringstream words(line);
    std::string rest;
    if (!(words >> count) || (words >> rest) || count < 0) {
      throw ViewFileError(path, "line " + std::to_string(line_number) + ": expected the number of views");
    }
  }
  const auto file_size = std::filesystem::file_size(path, ec);
  if (static_cast<unsigned long long>(count) > file_size / 14 + 1) {  // a view line has >= 14 characters
    throw ViewFileError(path, "claims " + std::to_string(count) + " views, more than the file can hold");
  }
  std::vector<View> views;
  views.reserve(static_cast<std::size_t>(count));
  for (long long i = 0; i < count; ++i) {
    if (!next_line()) {
      throw ViewFileError(path, "ends after " + std::to_string(i) + " of " + std::to_string(count) + " views");
    }
    std::istringstream words(line);
    double v[7];
    std::string rest;
    for (double& value : v) {
      std::string token;
      if (!(words >> token)) {
        throw ViewFileError(path, "line " + std::to_string(line_number) + ": expected x y z qx qy qz qw");
      }
      char* end = nullptr;
      value = std::strtod(token.c_str(), &end);
      if (end != token.c_str() + token.size() || !std::isfinite(value)) {
        throw ViewFileError(path, "line " + std::to_string(line_number) + ": '" + token + "' is not a finite number");
      }
    }
    if (words >> rest) throw ViewFileError(path, "line " + std::to_string(line_number) + ": extra value '" + rest + "'");
    try {
      views.push_back(viewFromPose(v[0], v[1], v[2], v[3], v[4], v[5], v[6]));
    } catch (const InvalidArgument& e) {
      throw ViewFileError(path, "line " + std::to_string(line_number) + ": " + e.what());
    }
  }
  if (next_line()) throw ViewFileError(path, "line " + std::to_string(line_number) + ": more lines than the " + std::to_string(count) + " views announced");
  return views;
}

View viewFromPose(double x, double y, double z, double qx, double qy, double qz, double qw) {
  for (const double value : {x, y, z, qx, qy, qz, qw}) {
    if (!std::isfinite(value)) throw InvalidArgument("a pose value, " + numberText(value) + ", is not finite");
  }
  Eigen::Quaterniond q(qw, qx, qy, qz);
  if (q.norm() < 1e-9) throw InvalidArgument("zero quaternion");
  q.normalize();  // non-unit quaternions are normalised, as documented
  View view;
  view.T_world_camera.linear() = q.toRotationMatrix();
  view.T_world_camera.translation() = Eigen::Vector3d(x, y, z);
  return view;
}

void saveViews(const std::filesystem::path& path, const std::vector<View>& views) {
  std::ofstream out(path, std::ios::trunc);
  if (!out) throw ViewFileError(path, "cannot open for writing");
  out << views.size() << '\n' << std::setprecision(std::numeric_limits<double>::max_digits10);
  for (const View& view : views) {
    // Adding +0.0 turns -0 into 0, so files read the same whatever the arithmetic's sign.
    const Eigen::Vector3d p = view.T_world_camera.translation().array() + 0.0;
    const Eigen::Vector4d q = canonicalQuaternion(view).coeffs().array() + 0.0;  // x y z w
    out << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << '\n';
  }
  out.flush();
  if (!out) throw ViewFileError(path, "write failed (disk full?)");
}

}  // namespace nbv::planner
