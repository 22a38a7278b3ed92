#pragma once
/// \file Candidate views (SEMANTICS.md "The planner"): the paper's 48-view dome and view files.
///
/// Thread-safety: the functions share no state and may run in several threads at once (two writing
/// one file excepted).

#include "nbv/errors.hpp"

#include <Eigen/Geometry>

#include <filesystem>
#include <string>
#include <vector>

namespace nbv::planner {

/// A candidate camera pose: optical frame (z forward, x along image columns, y along rows)
/// in the world (object) frame.
struct View {
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

/// The camera at `position` looking at `target` with the roll of SEMANTICS.md "The planner":
/// z towards the target,
/// x along the world's down direction (0, 0, -1) made perpendicular to z, y = z x x.
/// \throws InvalidArgument if the two points coincide or the view looks straight up or
/// down (the roll is then undefined).
View lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

/// The paper's 48 views (SEMANTICS.md "The planner"): indices 0-15 ring 1 (height 0.15 m, radius 0.6 m), then
/// ring 2 (height 0.35 m) and ring 3 (45 degrees up on a 0.6 m sphere around (0, 0, 0.35))
/// alternating, 22.5 degrees apart in azimuth from +x, counter-clockwise.
std::vector<View> dome48();

/// `count` views on a sphere of `radius_m` around `target`, spread by the Fibonacci
/// (golden-angle) lattice: heights z_i = 1 - (2 i + 1) / count of the unit sphere, azimuth
/// i times the golden angle, each looking at `target` with the roll of lookAt() (no view is
/// exactly above or below the target). \throws InvalidArgument if count is 0 or above
/// kMaxFibonacciViews, or the radius is not positive and finite.
std::vector<View> fibonacciSphere(std::size_t count, double radius_m, const Eigen::Vector3d& target);
/// The most views fibonacciSphere() makes: 10 million views are 1.3 GB of poses, and every
/// candidate is scored at each decision.
inline constexpr std::size_t kMaxFibonacciViews = 10'000'000;

/// The views of `views` whose position lies at height `min_z` [m] or above, in their order: a
/// sphere around an object on the ground keeps no view below the object's base.
std::vector<View> viewsAbove(const std::vector<View>& views, double min_z);

/// The view at position (x, y, z) [m] with orientation quaternion (qx, qy, qz, qw), normalised
/// (a line of a view file). \throws InvalidArgument for a non-finite value or a zero quaternion.
View viewFromPose(double x, double y, double z, double qx, double qy, double qz, double qw);

/// Reads a view file: `N`, then N lines `x y z qx qy qz qw`. Quaternions are normalised;
/// a zero or non-finite quaternion or position is refused.
/// \throws ViewFileError naming the file and line.
std::vector<View> loadViews(const std::filesystem::path& path);

/// Writes `views` in the format of loadViews(), quaternions with w >= 0 (w = 0: the last
/// non-zero of z, y, x positive). \throws ViewFileError if the file cannot be written.
void saveViews(const std::filesystem::path& path, const std::vector<View>& views);

/// The quaternion of a view in the sign convention of saveViews().
Eigen::Quaterniond canonicalQuaternion(const View& view);

}  // namespace nbv::planner
