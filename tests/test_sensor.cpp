// Meshes and the ideal depth camera: analytic scenes built in code, the bunny's normalisation,
// and bad meshes.
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/surface_sampling.hpp"

#include "expect_file_error.hpp"
#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>

namespace {

using nbv::sensor::DepthCamera;
using nbv::sensor::DepthCameraConfig;
using nbv::MeshFileError;
using nbv::sensor::RayScene;
using nbv::sensor::TriangleMesh;
namespace fs = std::filesystem;
using nbv::test::boxMesh;
using nbv::test::sphereMesh;

Eigen::Isometry3d lookingAlongX(const Eigen::Vector3d& position) {
  return nbv::test::lookAt(position, position + Eigen::Vector3d(1.0, 0.0, 0.0));
}

TEST(DepthCamera, PlaneDepthIsTheDistanceAlongTheAxisAtEveryPixel) {
  // The plane x = 0.8 seen from the origin looking along +x: z-depth 0.8 everywhere it is hit.
  const TriangleMesh plane{{{0.8f, -5.f, -5.f}, {0.8f, 5.f, -5.f}, {0.8f, 5.f, 5.f}, {0.8f, -5.f, 5.f}},
                           {{0, 1, 2}, {0, 2, 3}}};
  const RayScene scene(plane);
  const auto scan = DepthCamera().render(scene, lookingAlongX(Eigen::Vector3d::Zero()));
  ASSERT_EQ(scan.points_world.size(), 752u * 480u);  // 0.8 m on axis, < 1.5 m at the corners
  for (const float d : scan.depth_m) ASSERT_NEAR(d, 0.8, 1e-5);
  for (const auto& p : scan.points_world) ASSERT_NEAR(p.x(), 0.8, 1e-5);
}

TEST(DepthCamera, BoxFaceDepthsAndPointsOnTheSurface) {
  const TriangleMesh box = boxMesh({0.5f, -0.1f, -0.2f}, {0.7f, 0.15f, 0.1f});
  const RayScene scene(box);
  const nbv::sensor::PinholeCamera camera;
  const auto scan = DepthCamera().render(scene, lookingAlongX(Eigen::Vector3d::Zero()));
  // The principal point's pixel looks straight at the face x = 0.5.
  const auto centre = static_cast<std::size_t>(240) * 752 + 376;
  EXPECT_NEAR(scan.depth_m[centre], 0.5, 1e-5);
  std::size_t hits = 0;
  for (const auto& p : scan.points_world) {
    ++hits;
    ASSERT_NEAR(p.x(), 0.5, 1e-5);  // only the front face is visible from the origin
    ASSERT_GE(p.y(), -0.1f - 1e-5f);
    ASSERT_LE(p.y(), 0.15f + 1e-5f);
  }
  EXPECT_GT(hits, 10000u);
}

TEST(DepthCamera, SphereDepthMatchesTheAnalyticSphere) {
  const Eigen::Vector3f centre(0.6f, 0.0f, 0.0f);
  const float r = 0.25f;
  const int rings = 400;
  const double chord_error = r * (1.0 - std::cos(M_PI / rings));  // about 7.7e-6 m
  const RayScene scene(sphereMesh(centre, r, rings));
  const nbv::test::Sphere analytic{centre.cast<double>(), r};
  const nbv::sensor::PinholeCamera camera;
  const Eigen::Isometry3d T = lookingAlongX(Eigen::Vector3d::Zero());
  const auto scan = DepthCamera().render(scene, T);
  std::size_t checked = 0;
  for (int v = 0; v < camera.height; v += 7) {
    for (int u = 0; u < camera.width; u += 7) {
      const Eigen::Vector3d d_cam = camera.rayDirectionCamera(u, v);
      const auto t = analytic.intersect(Eigen::Vector3d::Zero(), T.linear() * d_cam);
      const float depth = scan.depth_m[static_cast<std::size_t>(v) * 752 + static_cast<std::size_t>(u)];
      if (!t) continue;
      // Along a ray the gap between the flat triangles and the sphere grows as 1 / cos of the
      // incidence angle: check the pixels that see the surface within ~70 degrees of normal.
      const Eigen::Vector3d d_world = T.linear() * d_cam;
      const double cos_incidence = -d_world.dot((*t * d_world - centre.cast<double>()) / r);
      if (cos_incidence < 0.3) continue;
      ASSERT_GT(depth, 0.0f) << u << ", " << v;
      ASSERT_NEAR(depth, *t * d_cam.z(), (chord_error / cos_incidence) * d_cam.z() + 1e-5) << u << ", " << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 500u);
  for (const auto& p : scan.points_world) ASSERT_NEAR((p - centre).norm(), r, chord_error + 1e-5);
}

TEST(DepthCamera, ParallelTilesEqualSerial) {
  const RayScene scene(sphereMesh({0.6f, 0.05f, 0.0f}, 0.2f, 60));
  DepthCameraConfig serial;
  serial.serial = true;
  DepthCameraConfig parallel;
  parallel.tile_size = 8;
  const auto T = lookingAlongX({0.0, 0.01, 0.02});
  const auto a = DepthCamera(serial).render(scene, T);
  const auto b = DepthCamera(parallel).render(scene, T);
  EXPECT_EQ(a.depth_m, b.depth_m);
  EXPECT_EQ(a.points_world, b.points_world);
}

TEST(DepthCamera, MaxRangeAndBadPosesAndSettings) {
  const TriangleMesh plane{{{2.0f, -5.f, -5.f}, {2.0f, 5.f, -5.f}, {2.0f, 5.f, 5.f}, {2.0f, -5.f, 5.f}}, {{0, 1, 2}, {0, 2, 3}}};
  const RayScene scene(plane);
  EXPECT_TRUE(DepthCamera().render(scene, lookingAlongX(Eigen::Vector3d::Zero())).points_world.empty());
  Eigen::Isometry3d nan_pose = lookingAlongX(Eigen::Vector3d::Zero());
  nan_pose.translation().x() = std::nan("");
  EXPECT_THROW(DepthCamera().render(scene, nan_pose), std::invalid_argument);
  Eigen::Isometry3d sheared = Eigen::Isometry3d::Identity();
  sheared.linear()(0, 1) = 0.5;
  EXPECT_THROW(DepthCamera().render(scene, sheared), std::invalid_argument);
  DepthCameraConfig bad;
  bad.max_range_m = 0.0;
  EXPECT_THROW(DepthCamera{bad}, std::invalid_argument);
}

TEST(Mesh, BunnyNormalisation) {
  const fs::path bunny = nbv::sensor::resolveModel("bunny");
  nbv::sensor::MeshLoadReport report;
  TriangleMesh mesh = nbv::sensor::loadMesh(bunny, &report);
  EXPECT_GT(mesh.triangles.size(), 70000u);
  const TriangleMesh original = mesh;
  const auto n = nbv::sensor::normalizeMesh(mesh);
  const Eigen::AlignedBox3d b = nbv::sensor::meshBounds(mesh);
  EXPECT_NEAR(b.sizes().maxCoeff(), 0.5, 1e-6);
  EXPECT_NEAR(b.min().z(), 0.0, 1e-6);
  EXPECT_NEAR(b.center().x(), 0.0, 1e-6);
  EXPECT_NEAR(b.center().y(), 0.0, 1e-6);
  // The kept transform maps the original onto the normalised mesh.
  EXPECT_TRUE((n.T_normalized_original * original.vertices[123].cast<double>()).isApprox(mesh.vertices[123].cast<double>(), 1e-6));
}

TEST(Mesh, EveryModelLoads) {
  for (const nbv::sensor::StandardModel& model : nbv::sensor::standardModels()) {
    TriangleMesh mesh = nbv::sensor::loadMesh(nbv::sensor::resolveModel(model.name));
    EXPECT_GT(mesh.triangles.size(), 400u) << model.name;
    for (const auto up : {nbv::sensor::UpAxis::Z, nbv::sensor::UpAxis::Y}) {
      TriangleMesh placed = mesh;
      nbv::sensor::normalizeMesh(placed, {up});
      const Eigen::AlignedBox3d box = nbv::sensor::meshBounds(placed);
      EXPECT_NEAR(box.sizes().maxCoeff(), 0.5, 1e-6) << model.name;
      EXPECT_NEAR(box.min().z(), 0.0, 1e-6) << model.name;
      EXPECT_NEAR(box.center().x(), 0.0, 1e-6) << model.name;
      // The ideal camera sees it from the dome's first view.
      const nbv::sensor::DepthScan scan =
          nbv::sensor::DepthCamera().render(nbv::sensor::RayScene(placed), nbv::test::lookAt({0.6, 0.0, 0.15}, {0, 0, 0.15}));
      EXPECT_GT(scan.points_world.size(), 5000u) << model.name;
    }
  }
  const fs::path bunny = nbv::sensor::resolveModel("bunny");
  EXPECT_EQ(nbv::sensor::resolveModel(bunny.string()), bunny);  // a path stays itself
}

TEST(Mesh, AMissingModelSaysWhatToDo) {
  try {
    nbv::sensor::resolveModel("some/path.off");
    FAIL() << "no error";
  } catch (const nbv::MeshFileError& e) {
    EXPECT_NE(std::string(e.what()).find("some/path.off: no such file, and not a standard model name (bunny, "),
              std::string::npos) << e.what();
  }
  try {
    nbv::sensor::resolveModel("bunny", {"/nonexistent/models", "/nonexistent/shared"});
    FAIL() << "no error";
  } catch (const nbv::MeshFileError& e) {
    EXPECT_STREQ(e.what(), "bunny00.off: the standard model 'bunny' is not in /nonexistent/models, /nonexistent/shared: "
                           "run `nbv models fetch` (Python: nbv.fetch_models()), or point NBV_MODELS_DIR at a folder "
                           "that has it");
  }
}

void write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

void expectRefused(const fs::path& path) {
  nbv::test::expectFileError<MeshFileError>(path, [](const fs::path& p) { nbv::sensor::loadMesh(p); });
}

TEST(Mesh, DegenerateTrianglesAreDroppedAndCounted) {
  nbv::test::TempDir dir;
  // Two good triangles, one with a repeated vertex, one with zero area (collinear).
  write(dir / "d.off", "OFF\n5 4 0\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n1 1 0\n3 0 1 2\n3 1 4 2\n3 0 0 1\n3 0 1 3\n");
  nbv::sensor::MeshLoadReport report;
  const TriangleMesh mesh = nbv::sensor::loadMesh(dir / "d.off", &report);
  EXPECT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(report.degenerate_dropped, 2u);
}

TEST(Mesh, OffCommentsRunToTheEndOfTheirLine) {
  nbv::test::TempDir dir;
  write(dir / "c.off", "OFF # a cube corner\n# counts\n4 2 0\n0 0 0 # origin\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2 #\n3 0 2 3\n");
  const TriangleMesh mesh = nbv::sensor::loadMesh(dir / "c.off");
  ASSERT_EQ(mesh.vertices.size(), 4u);
  ASSERT_EQ(mesh.triangles.size(), 2u);
  EXPECT_EQ(mesh.triangles[1], Eigen::Vector3i(0, 2, 3));
}

TEST(Mesh, BadMeshesAreRefusedNamingTheFile) {
  nbv::test::TempDir dir;
  expectRefused(dir / "missing.off");
  fs::create_directory(dir / "dir.off");
  expectRefused(dir / "dir.off");
  const std::pair<const char*, const char*> bad_files[] = {
      {"empty.off", ""},
      {"notris.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"},
      {"nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"},
      {"index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"},  // out-of-range index
      {"garbage.stl", "this is not a mesh at all\n"},
      {"onlydegenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"},
      // Refused before assimp allocates for the claimed counts (that once exhausted memory).
      {"bomb.off", "OFF\n1000000000 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"nocounts.off", "OFF\nthree vertices\n"},
  };
  for (const auto& [name, text] : bad_files) {
    write(dir / name, text);
    expectRefused(dir / name);
  }
}

}  // namespace

namespace {

TEST(SurfaceSampling, AreaUniformOnTwoTrianglesOfDifferentArea) {
  // Triangle A has area 0.5, triangle B area 1.5 (three times A), far apart on x.
  const TriangleMesh mesh{{{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f},
                           {10.f, 0.f, 0.f}, {13.f, 0.f, 0.f}, {10.f, 1.f, 0.f}},
                          {{0, 1, 2}, {3, 4, 5}}};
  EXPECT_NEAR(nbv::sensor::surfaceArea(mesh), 2.0, 1e-12);
  const auto points = nbv::sensor::sampleSurface(mesh, 100000, 42);
  const auto on_b = std::count_if(points.begin(), points.end(), [](const Eigen::Vector3f& p) { return p.x() >= 10.f; });
  // Expected 75,000; the binomial standard deviation is ~137, so 5 sigma is ~700.
  EXPECT_NEAR(static_cast<double>(on_b), 75000.0, 700.0);
  // Uniform inside a triangle: the half of A nearer its right angle (x + y < sqrt(0.5)) holds
  // half its area.
  std::size_t a_total = 0, a_inner = 0;
  for (const auto& p : points) {
    if (p.x() >= 10.f) continue;
    ++a_total;
    ASSERT_GE(p.x(), 0.f);
    ASSERT_GE(p.y(), 0.f);
    ASSERT_LE(p.x() + p.y(), 1.f + 1e-6f);
    if (p.x() + p.y() < std::sqrt(0.5f)) ++a_inner;
  }
  EXPECT_NEAR(static_cast<double>(a_inner) / static_cast<double>(a_total), 0.5, 0.02);
  // Seeded: same seed, same points; another seed, other points.
  EXPECT_EQ(nbv::sensor::sampleSurface(mesh, 100, 42), nbv::sensor::sampleSurface(mesh, 100, 42));
  EXPECT_NE(nbv::sensor::sampleSurface(mesh, 100, 42), nbv::sensor::sampleSurface(mesh, 100, 43));
}

TEST(SurfaceSampling, DefaultCountIsDenseOnTheNormalisedBunny) {
  TriangleMesh bunny = nbv::sensor::loadMesh(nbv::sensor::resolveModel("bunny"));
  nbv::sensor::normalizeMesh(bunny);
  const double area = nbv::sensor::surfaceArea(bunny);
  // Mean spacing sqrt(area / N) well under (2.5 times below) the 5 mm threshold of Eq. 15.
  const double spacing = std::sqrt(area / static_cast<double>(nbv::sensor::kDefaultGroundTruthPoints));
  EXPECT_NEAR(area, 0.59, 0.01);
  EXPECT_LT(spacing, 0.002) << "area " << area << " m^2";
}

}  // namespace

namespace {

TEST(DepthCamera, AxialGaussianNoiseHasTheStatedSpreadAndIsSeeded) {
  // The plane x = 1 seen along +x: depth 1 everywhere, so sigma = a + b.
  const TriangleMesh plane{{{1.0f, -5.f, -5.f}, {1.0f, 5.f, -5.f}, {1.0f, 5.f, 5.f}, {1.0f, -5.f, 5.f}}, {{0, 1, 2}, {0, 2, 3}}};
  const RayScene scene(plane);
  DepthCameraConfig config;
  config.noise.kind = nbv::sensor::DepthNoise::Kind::AxialGaussian;
  config.noise.a_m = 0.001;
  config.noise.b_per_m = 0.002;
  config.noise.seed = 7;
  const auto T = lookingAlongX(Eigen::Vector3d::Zero());
  const auto scan = DepthCamera(config).render(scene, T);
  double sum = 0.0, sum_sq = 0.0;
  for (const float d : scan.depth_m) {
    sum += d - 1.0;
    sum_sq += (d - 1.0) * (d - 1.0);
  }
  const double n = static_cast<double>(scan.depth_m.size());
  EXPECT_NEAR(sum / n, 0.0, 5e-5);                        // unbiased
  EXPECT_NEAR(std::sqrt(sum_sq / n), 0.003, 0.003 * 0.01);  // sigma = a + b z^2 = 3 mm
  // Points move along their own pixel's ray: still on the line through the camera centre.
  const nbv::sensor::PinholeCamera camera;
  const std::size_t i = 100 * 752 + 200;
  const Eigen::Vector3d ray = T.linear() * camera.rayDirectionCamera(200, 100);
  EXPECT_NEAR(ray.cross(scan.points_world[i].cast<double>()).norm(), 0.0, 1e-5);
  // Seeded, and independent of threads.
  DepthCameraConfig serial = config;
  serial.serial = true;
  EXPECT_EQ(DepthCamera(serial).render(scene, T).depth_m, scan.depth_m);
  DepthCameraConfig other = config;
  other.noise.seed = 8;
  EXPECT_NE(DepthCamera(other).render(scene, T).depth_m, scan.depth_m);
}

TEST(DepthCamera, HolesDropTheStatedShareAndSquaresAndAreSeeded) {
  // The plane x = 1 fills the image: every pixel returns but the holes.
  const TriangleMesh plane{{{1.0f, -5.f, -5.f}, {1.0f, 5.f, -5.f}, {1.0f, 5.f, 5.f}, {1.0f, -5.f, 5.f}}, {{0, 1, 2}, {0, 2, 3}}};
  const RayScene scene(plane);
  const auto T = lookingAlongX(Eigen::Vector3d::Zero());
  const std::size_t pixels = 752u * 480u;
  DepthCameraConfig config;
  config.holes = {0.05, 0, 40, 3};
  const auto scattered = DepthCamera(config).render(scene, T);
  const double share = 1.0 - static_cast<double>(scattered.points_world.size()) / pixels;
  EXPECT_NEAR(share, 0.05, 0.002);  // 3 sigma of a binomial share over 360,960 pixels: 0.0011
  // One 40-pixel square and no scattered holes: exactly a square of 1,600 zero pixels.
  config.holes = {0.0, 1, 40, 3};
  const auto square = DepthCamera(config).render(scene, T);
  ASSERT_EQ(square.points_world.size(), pixels - 1600u);
  int u_min = 752, u_max = -1, v_min = 480, v_max = -1;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 752; ++u) {
      if (square.depth_m[static_cast<std::size_t>(v) * 752 + static_cast<std::size_t>(u)] != 0.0f) continue;
      u_min = std::min(u_min, u), u_max = std::max(u_max, u), v_min = std::min(v_min, v), v_max = std::max(v_max, v);
    }
  }
  EXPECT_EQ(u_max - u_min, 39);
  EXPECT_EQ(v_max - v_min, 39);
  // Seeded and independent of threads; another seed, other holes.
  config.holes = {0.05, 2, 40, 3};
  DepthCameraConfig serial = config;
  serial.serial = true;
  const auto holes = DepthCamera(config).render(scene, T);
  EXPECT_EQ(DepthCamera(serial).render(scene, T).depth_m, holes.depth_m);
  DepthCameraConfig other = config;
  other.holes.seed = 4;
  EXPECT_NE(DepthCamera(other).render(scene, T).depth_m, holes.depth_m);
  // Bad settings are refused by value.
  for (const nbv::sensor::DepthHoles bad : {nbv::sensor::DepthHoles{-0.1, 0, 40, 0}, nbv::sensor::DepthHoles{1.5, 0, 40, 0},
                                            nbv::sensor::DepthHoles{0.0, -1, 40, 0}, nbv::sensor::DepthHoles{0.0, 1, 0, 0}}) {
    DepthCameraConfig refused;
    refused.holes = bad;
    EXPECT_THROW(DepthCamera{refused}, nbv::InvalidArgument);
  }
}

}  // namespace

namespace {

TEST(PixelRays, PresetsHaveTheSpecRayCounts) {
  const nbv::sensor::PinholeCamera camera;
  EXPECT_EQ(nbv::sensor::pixelRays(camera, nbv::sensor::PixelSampling::full()).size(), 360960u);
  const auto released = nbv::sensor::pixelRays(camera, nbv::sensor::PixelSampling::released());
  EXPECT_EQ(released.size(), 950u);  // 38 columns (188..558) x 25 rows (120..360)
  EXPECT_EQ(released.front().u, 188);
  EXPECT_EQ(released.front().v, 120);
  EXPECT_EQ(released.back().u, 558);
  EXPECT_EQ(released.back().v, 360);
  EXPECT_THROW(nbv::sensor::pixelRays(camera, {0, 1.0}), std::invalid_argument);
  EXPECT_THROW(nbv::sensor::pixelRays(camera, {1, 0.0}), std::invalid_argument);
}

TEST(PixelRays, ReleasedShippedIsTheWindowOfTheSwappedImage) {
  // The shipped launch file: a 480 x 752 image (sides swapped) with cx 376.5, cy 240.5 kept:
  // columns 120..360 (25) and rows 188..558 (38), rows beyond 479 outside the real image.
  const nbv::sensor::PinholeCamera camera;
  const auto shipped = nbv::sensor::pixelRays(camera, nbv::sensor::PixelSampling::fromName("released-shipped"));
  ASSERT_EQ(shipped.size(), 950u);
  EXPECT_EQ(shipped.front().u, 120);
  EXPECT_EQ(shipped.front().v, 188);
  EXPECT_EQ(shipped[24].u, 360);
  EXPECT_EQ(shipped[24].v, 188);
  EXPECT_EQ(shipped.back().u, 360);
  EXPECT_EQ(shipped.back().v, 558);
  // Each ray is the pixel's ray: ((u - cx) / fx, (v - cy) / fy, 1) normalised.
  for (const auto& ray : shipped) {
    const Eigen::Vector3d by_hand = Eigen::Vector3d((ray.u - 376.5) / camera.fx, (ray.v - 240.5) / camera.fy, 1.0).normalized();
    EXPECT_EQ(ray.direction_camera, by_hand);
  }
  // Off the optical axis: the window's centre pixel (240, 373) lies 17 degrees to the side
  // (atan(136.5 / fx)) and 16.5 degrees down (atan(132.5 / fy)).
  const double centre_u = 0.5 * (shipped.front().u + shipped.back().u), centre_v = 0.5 * (shipped.front().v + shipped.back().v);
  EXPECT_NEAR(std::atan((376.5 - centre_u) / camera.fx) * 180.0 / M_PI, 16.94, 0.01);
  EXPECT_NEAR(std::atan((centre_v - 240.5) / camera.fy) * 180.0 / M_PI, 16.48, 0.01);
}

TEST(PixelRays, DepthCameraAndIgRaySetShareThePixelRay) {
  // Every rendered point lies exactly on the IG ray of its pixel (both come from
  // PinholeCamera::rayDirectionCamera).
  const TriangleMesh plane{{{0.9f, -5.f, -5.f}, {0.9f, 5.f, -5.f}, {0.9f, 5.f, 5.f}, {0.9f, -5.f, 5.f}}, {{0, 1, 2}, {0, 2, 3}}};
  const RayScene scene(plane);
  const auto T = nbv::test::lookAt({0.1, 0.2, 0.3}, {1.0, 0.25, 0.2});
  const auto scan = DepthCamera().render(scene, T);
  const nbv::sensor::PinholeCamera camera;
  for (const auto& ray : nbv::sensor::pixelRays(camera, {37, 1.0})) {
    const std::size_t i = static_cast<std::size_t>(ray.v) * 752 + static_cast<std::size_t>(ray.u);
    ASSERT_GT(scan.depth_m[i], 0.0f);
    const Eigen::Vector3f direction = (T.linear() * ray.direction_camera).cast<float>();
    const auto t = scene.intersect(T.translation().cast<float>(), direction, 1.5f);
    ASSERT_TRUE(t.has_value());
    const Eigen::Vector3f expected = T.translation().cast<float>() + t->distance_m * direction;
    // Same pixel -> ray, same float arithmetic: the very same point.
    const std::size_t rank = static_cast<std::size_t>(std::count_if(scan.depth_m.begin(), scan.depth_m.begin() + static_cast<long>(i), [](float d) { return d > 0.0f; }));
    ASSERT_EQ(scan.points_world[rank], expected) << ray.u << ", " << ray.v;
  }
}

}  // namespace

namespace {

TEST(Mesh, ObjStlAndPlyLoadThroughAssimp) {
  nbv::test::TempDir dir;
  // One unit square (two triangles) in each format.
  write(dir / "q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n");
  write(dir / "q.stl",
        "solid q\n"
        " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n"
        " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\n"
        "endsolid q\n");
  write(dir / "q.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  for (const char* name : {"q.obj", "q.stl", "q.ply"}) {
    const TriangleMesh mesh = nbv::sensor::loadMesh(dir / name);
    EXPECT_EQ(mesh.triangles.size(), 2u) << name;  // the PLY quad is triangulated
    EXPECT_NEAR(nbv::sensor::surfaceArea(mesh), 1.0, 1e-6) << name;
  }
}

}  // namespace

namespace {

/// Nearest hit of a ray with a mesh, in double precision (Moller-Trumbore over every triangle).
std::optional<double> bruteForceHit(const TriangleMesh& mesh, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  std::optional<double> best;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(t[0])].cast<double>();
    const Eigen::Vector3d e1 = mesh.vertices[static_cast<std::size_t>(t[1])].cast<double>() - a;
    const Eigen::Vector3d e2 = mesh.vertices[static_cast<std::size_t>(t[2])].cast<double>() - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::fabs(det) < 1e-15) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(p) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    const double dist = e2.dot(q) / det;
    if (dist > 0.0 && (!best || dist < *best)) best = dist;
  }
  return best;
}

TEST(DepthCamera, SphereMeshDepthEqualsExactRayTriangleDistance) {
  // The depth of the tessellated sphere at chosen pixels equals the exact (double precision)
  // ray-triangle distance to within 1e-5 m.
  const TriangleMesh sphere = sphereMesh({0.6f, 0.02f, -0.01f}, 0.25f, 40);
  const RayScene scene(sphere);
  const auto T = lookingAlongX(Eigen::Vector3d::Zero());
  const auto scan = DepthCamera().render(scene, T);
  const nbv::sensor::PinholeCamera camera;
  std::size_t checked = 0;
  for (const auto& ray : nbv::sensor::pixelRays(camera, {23, 1.0})) {
    const Eigen::Vector3d d = T.linear() * ray.direction_camera;
    const auto exact = bruteForceHit(sphere, Eigen::Vector3d::Zero(), d);
    const float depth = scan.depth_m[static_cast<std::size_t>(ray.v) * 752 + static_cast<std::size_t>(ray.u)];
    if (!exact) {
      EXPECT_EQ(depth, 0.0f) << ray.u << ", " << ray.v;
      continue;
    }
    ASSERT_NEAR(depth, *exact * ray.direction_camera.z(), 1e-5) << ray.u << ", " << ray.v;
    ++checked;
  }
  EXPECT_GT(checked, 100u);
}

}  // namespace
