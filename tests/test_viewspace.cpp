// The paper's 48-view dome (SEMANTICS.md "The planner") and view files.
#include "nbv/planner/viewspace.hpp"

#include "expect_file_error.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace {

using nbv::planner::View;
namespace fs = std::filesystem;

/// True if the view's optical axis passes through `target` (z points at it).
void expectLooksAt(const View& v, const Eigen::Vector3d& target) {
  const Eigen::Vector3d to_target = (target - v.T_world_camera.translation()).normalized();
  EXPECT_NEAR(v.T_world_camera.linear().col(2).dot(to_target), 1.0, 1e-12);
  // x is the world's down direction made perpendicular to z: no component along world y
  // once projected, and pointing down.
  EXPECT_LT(v.T_world_camera.linear().col(0).z(), 0.0);
  EXPECT_NEAR(v.T_world_camera.linear().determinant(), 1.0, 1e-12);
}

TEST(Viewspace, Dome48MatchesSpec) {
  const auto views = nbv::planner::dome48();
  ASSERT_EQ(views.size(), 48u);
  const double step = M_PI / 8.0;
  for (int i = 0; i < 16; ++i) {
    const Eigen::Vector3d p = views[static_cast<std::size_t>(i)].T_world_camera.translation();
    EXPECT_TRUE(p.isApprox(Eigen::Vector3d(0.6 * std::cos(step * i), 0.6 * std::sin(step * i), 0.15), 1e-12)) << i;
    expectLooksAt(views[static_cast<std::size_t>(i)], {0.0, 0.0, 0.15});
  }
  for (int j = 0; j < 16; ++j) {
    const View& ring2 = views[static_cast<std::size_t>(16 + 2 * j)];
    const View& ring3 = views[static_cast<std::size_t>(17 + 2 * j)];
    EXPECT_TRUE(ring2.T_world_camera.translation().isApprox(
        Eigen::Vector3d(0.6 * std::cos(step * j), 0.6 * std::sin(step * j), 0.35), 1e-12)) << j;
    expectLooksAt(ring2, {0.0, 0.0, 0.35});
    const Eigen::Vector3d p3 = ring3.T_world_camera.translation();
    EXPECT_NEAR(p3.z(), 0.7743, 1e-4) << j;                         // 0.35 + 0.6 sin 45
    EXPECT_NEAR(p3.head<2>().norm(), 0.4243, 1e-4) << j;             // 0.6 cos 45
    EXPECT_NEAR(std::atan2(p3.y(), p3.x()), std::remainder(step * j, 2 * M_PI), 1e-12) << j;
    EXPECT_NEAR((p3 - Eigen::Vector3d(0, 0, 0.35)).norm(), 0.6, 1e-12);
    expectLooksAt(ring3, {0.0, 0.0, 0.35});
  }
  // View 0 as SEMANTICS.md "The planner" writes it: (0.6, 0, 0.15), quaternion (x, y, z, w) = (-0.7071068, 0, 0.7071068, 0).
  const Eigen::Quaterniond q = nbv::planner::canonicalQuaternion(views[0]);
  EXPECT_NEAR(q.x(), -0.7071068, 1e-7);
  EXPECT_NEAR(q.y(), 0.0, 1e-7);
  EXPECT_NEAR(q.z(), 0.7071068, 1e-7);
  EXPECT_NEAR(q.w(), 0.0, 1e-7);
}

TEST(Viewspace, LookAtStraightDownIsRefused) {
  EXPECT_THROW(nbv::planner::lookAt({0, 0, 1}, {0, 0, 0}), std::invalid_argument);
  EXPECT_THROW(nbv::planner::lookAt({0, 0, 1}, {0, 0, 1}), std::invalid_argument);
}

TEST(Viewspace, SaveLoadRoundTrip) {
  nbv::test::TempDir dir;
  const auto views = nbv::planner::dome48();
  nbv::planner::saveViews(dir / "v.txt", views);
  const auto loaded = nbv::planner::loadViews(dir / "v.txt");
  ASSERT_EQ(loaded.size(), views.size());
  for (std::size_t i = 0; i < views.size(); ++i) {
    EXPECT_TRUE(loaded[i].T_world_camera.isApprox(views[i].T_world_camera, 1e-12)) << i;
  }
  std::ifstream in(dir / "v.txt");
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  EXPECT_EQ(first, "48");
}

TEST(Viewspace, NonUnitQuaternionsAreNormalised) {
  nbv::test::TempDir dir;
  std::ofstream(dir / "v.txt") << "1\n0.6 0 0.15 -2 0 2 0\n";
  const auto views = nbv::planner::loadViews(dir / "v.txt");
  EXPECT_TRUE(views[0].T_world_camera.isApprox(nbv::planner::dome48()[0].T_world_camera, 1e-12));
}

TEST(Viewspace, BadViewFilesAreRefusedNamingFileAndLine) {
  nbv::test::TempDir dir;
  auto load = [](const fs::path& p) { nbv::planner::loadViews(p); };
  nbv::test::expectFileError<nbv::ViewFileError>(dir / "missing.txt", load, "no such file");
  const struct { const char* name; const char* text; const char* fragment; } cases[] = {
      {"empty.txt", "", "empty"},
      {"count.txt", "two\n", "line 1"},
      {"short.txt", "2\n0 0 0 0 0 0 1\n", "ends after 1 of 2"},
      {"nan.txt", "1\n0 nan 0 0 0 0 1\n", "line 2"},
      {"inf.txt", "1\n0 0 0 0 0 inf 1\n", "line 2"},
      {"zeroq.txt", "1\n0 0 0 0 0 0 0\n", "zero quaternion"},
      {"fields.txt", "1\n0 0 0 0 0 1\n", "line 2"},
      {"extra.txt", "1\n0 0 0 0 0 0 1 5\n", "extra value"},
      {"more.txt", "1\n0 0 0 0 0 0 1\n0 0 0 0 0 0 1\n", "more lines"},
      {"bomb.txt", "1000000000000\n0 0 0 0 0 0 1\n", "more than the file can hold"},
  };
  for (const auto& c : cases) {
    std::ofstream(dir / c.name) << c.text;
    nbv::test::expectFileError<nbv::ViewFileError>(dir / c.name, load, c.fragment);
  }
  EXPECT_TRUE(nbv::planner::loadViews([&] {
                std::ofstream(dir / "zero.txt") << "0\n";
                return dir / "zero.txt";
              }()).empty());
}

}  // namespace
