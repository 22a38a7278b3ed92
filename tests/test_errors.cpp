// Every `\throws` of the public headers, thrown as documented: the exact nbv type of
// nbv/errors.hpp (EXPECT_THROW also accepts a subclass, so each check names the most derived
// type the header promises), one test per documented function.
#include "nbv/errors.hpp"
#include "nbv/grid/huge_pages.hpp"
#include "nbv/ig/evaluator.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/ig/map_snapshot.hpp"
#include "nbv/ig/reference_evaluator.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/planner/evaluation.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/utility.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/point_cloud_io.hpp"
#include "nbv/sensor/surface_sampling.hpp"

#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <new>
#include <type_traits>

namespace nbv {
namespace {

using ig::EvaluateOptions;
using ig::IgEvaluator;
using grid::OccupancyMap;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Calls `f` and checks that it throws exactly `E` (not a subclass) with a non-empty message.
template <class E, class F>
void expectExactly(F&& f, const char* what) {
  try {
    f();
    ADD_FAILURE() << what << ": no exception";
  } catch (const E& e) {
    EXPECT_EQ(typeid(e), typeid(E)) << what << ": " << typeid(e).name();
    EXPECT_STRNE(e.what(), "") << what;
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": threw " << typeid(e).name() << ": " << e.what();
  }
}

TEST(Errors, TheHierarchyKeepsTheStandardBases) {
  static_assert(std::is_base_of_v<std::invalid_argument, InvalidArgument>);
  static_assert(std::is_base_of_v<std::runtime_error, CapacityError>);
  static_assert(std::is_base_of_v<FileError, MapFileError> && std::is_base_of_v<FileError, CloudFileError> &&
                std::is_base_of_v<FileError, MeshFileError> && std::is_base_of_v<FileError, ViewFileError>);
  const MapFileError e("/tmp/x.vdb", "truncated");
  EXPECT_STREQ(e.what(), "/tmp/x.vdb: truncated");
  EXPECT_EQ(e.path(), std::filesystem::path("/tmp/x.vdb"));
}

TEST(Errors, MessagesPrintNumbersShortestAndExact) {
  EXPECT_EQ(numberText(0.01), "0.01");
  EXPECT_EQ(numberText(0.3f), "0.3");  // the float's own shortest text, not its double's
  EXPECT_EQ(numberText(-2.5e-7), "-2.5e-07");
  EXPECT_EQ(numberText(4100.0), "4100");
  EXPECT_EQ(numberText(0.0001), "0.0001");  // %g style: not "1e-04"
  EXPECT_EQ(numberText(1e-5), "1e-05");
  EXPECT_EQ(numberText(std::numeric_limits<double>::quiet_NaN()), "nan");
  try {
    planner::fibonacciSphere(4, -0.25, Eigen::Vector3d::Zero());
    ADD_FAILURE() << "a negative radius was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "fibonacciSphere: radius -0.25 m must be positive");
  }
}

OccupancyMap smallMap() {
  OccupancyMap map;
  map.integrate({Eigen::Vector3f(0.305f, 0.005f, 0.005f)}, Eigen::Vector3f(0.005f, 0.005f, 0.005f));
  return map;
}

const std::vector<Eigen::Vector3d> kForward = {Eigen::Vector3d::UnitZ()};
const std::vector<Eigen::Isometry3d> kOrigin = {Eigen::Isometry3d::Identity()};

// --- grid ------------------------------------------------------------------------------------

TEST(Errors, MapConfigValidateAndTheMapConstructor) {
  grid::MapConfig config;
  config.resolution = -0.01;
  expectExactly<InvalidArgument>([&] { config.validate(); }, "MapConfig::validate");
  expectExactly<InvalidArgument>([&] { OccupancyMap{config}; }, "OccupancyMap()");
  // Finer than OpenVDB's transforms allow: refused by nbv, not by OpenVDB's ArithmeticError.
  config.resolution = 1e-5;
  try {
    OccupancyMap{config};
    ADD_FAILURE() << "a resolution of 1e-5 m was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "invalid map configuration: resolution = 1e-05 (must be finite and >= 0.0001 m)");
  }
  config.resolution = grid::MapConfig::kMinResolution;
  OccupancyMap finest(config);
  finest.integrate({Eigen::Vector3f(0.01005f, 0.00005f, 0.00005f)}, Eigen::Vector3f(0.00005f, 0.00005f, 0.00005f));
  EXPECT_EQ(finest.measuredCount(), 101u);  // voxels 0 to 99 missed, then the hit in voxel 100
}

TEST(Errors, Integrate) {
  OccupancyMap map;
  expectExactly<InvalidArgument>([&] { map.integrate(std::vector<Eigen::Vector3f>{}, Eigen::Vector3f(NAN, 0, 0)); }, "integrate: NaN origin");
  grid::IntegrateOptions capped;
  capped.max_measured_voxels = 1;
  expectExactly<CapacityError>([&] { map.integrate({Eigen::Vector3f(0.3f, 0, 0)}, Eigen::Vector3f::Zero(), capped); },
                               "integrate: cap");
  EXPECT_EQ(map.measuredCount(), 0u);  // refused before the map changed
}

TEST(Errors, DirectEdits) {
  OccupancyMap map = smallMap();
  expectExactly<InvalidArgument>([&] { map.setLogOdds({0, 0, 0}, static_cast<float>(kNaN)); }, "setLogOdds");
  expectExactly<InvalidArgument>([&] { map.setProximity({90, 90, 90}, 0); }, "setProximity: distance");
  expectExactly<InvalidArgument>([&] { map.setProximity({0, 0, 0}, 3); }, "setProximity: measured voxel");
}

TEST(Errors, EvaluateOptionsValidateAndValidateViews) {
  EvaluateOptions options;
  options.walk.rays_per_task = 0;
  expectExactly<InvalidArgument>([&] { options.validate(); }, "EvaluateOptions::validate");
  options = EvaluateOptions{};
  options.table.metrics.clear();
  expectExactly<InvalidArgument>([&] { options.validate(); }, "EvaluateOptions::validate: no metric");
  const OccupancyMap map = smallMap();
  expectExactly<InvalidArgument>([&] { ig::validateViews(map, kOrigin, {}, 1.5); }, "validateViews: no ray");
  Eigen::Isometry3d sheared = Eigen::Isometry3d::Identity();
  sheared.linear()(0, 1) = 0.5;
  expectExactly<InvalidArgument>([&] { ig::validateViews(map, std::vector{sheared}, kForward, 1.5); },
                                 "validateViews: not rigid");
}

TEST(Errors, IgEvaluatorEvaluate) {
  const OccupancyMap map = smallMap();
  IgEvaluator evaluator;
  expectExactly<InvalidArgument>([&] { evaluator.evaluate(kOrigin, kForward); }, "evaluate: no refresh");
  evaluator.refresh(map, ig::snapshotFor(std::vector{ig::Metric::OcclusionAware}));  // no frontier flags
  expectExactly<InvalidArgument>([&] { evaluator.evaluate(kOrigin, kForward); }, "evaluate: fv without frontier flags");
  evaluator.refresh(map);
  expectExactly<InvalidArgument>([&] { evaluator.evaluate(kOrigin, {}); }, "evaluate: no ray");
  expectExactly<InvalidArgument>([&] { ig::evaluate(map, kOrigin, {}); }, "ig::evaluate: no ray");
  ig::WalkOptions walk;
  walk.max_ray_depth = kNaN;
  expectExactly<InvalidArgument>([&] { evaluator.evaluate(kOrigin, kForward, {}, walk); }, "evaluate: depth");
  // The snapshot cap: refused on a first snapshot, and re-checked on a snapshot already held.
  ig::SnapshotOptions small;
  small.max_snapshot_bytes = 16;
  expectExactly<CapacityError>([&] { IgEvaluator().refresh(map, small); }, "refresh: cap, first snapshot");
  expectExactly<CapacityError>([&] { ig::evaluate(map, kOrigin, kForward, {small, {}, {}}); },
                               "ig::evaluate: cap");
  expectExactly<CapacityError>([&] { evaluator.refresh(map, small); }, "refresh: smaller cap, snapshot held");
  expectExactly<InvalidArgument>([&] { evaluator.evaluate(kOrigin, kForward); }, "evaluate: no snapshot after a refused refresh");
  evaluator.refresh(map);
  EXPECT_NO_THROW(evaluator.evaluate(kOrigin, kForward));  // and recovers
}

TEST(Errors, IgTableValue) {
  EvaluateOptions options;
  options.table.metrics = {ig::Metric::OcclusionAware, ig::Metric::ProximityCount};
  const ig::IgTable table = ig::evaluate(smallMap(), kOrigin, kForward, options);
  ASSERT_EQ(table.views(), 1u);
  EXPECT_EQ(table.value(0, 1), table.value(0, ig::Metric::ProximityCount));
  expectExactly<InvalidArgument>([&] { table.value(1, 0); }, "value: view past the end");
  expectExactly<InvalidArgument>([&] { table.value(0, 2); }, "value: column past the end");
  expectExactly<InvalidArgument>([&] { table.value(0, ig::Metric::AverageEntropy); }, "value: a metric not in the table");
}

TEST(Errors, MapSnapshotUpdate) {
  const OccupancyMap map = smallMap();
  ig::MapSnapshot snapshot;
  const auto model = ig::SnapshotOptions{}.voxelModel(map.config());
  expectExactly<CapacityError>([&] { snapshot.update(map, model, 16); }, "MapSnapshot::update");
  snapshot.update(map, model, std::size_t{1} << 30);
  expectExactly<CapacityError>([&] { snapshot.update(map, model, 16); }, "MapSnapshot::update, held");
}

TEST(Errors, ReferenceEvaluator) {
  OccupancyMap far;
  far.setLogOdds({40000, 0, 0}, 1.0f);
  expectExactly<InvalidArgument>([&] { ig::ReferenceEvaluator{far}; }, "ReferenceEvaluator(): key range");
  const ig::ReferenceEvaluator reference(smallMap());
  expectExactly<InvalidArgument>([&] { reference.evaluate(kOrigin, {}); }, "ReferenceEvaluator::evaluate");
}

TEST(Errors, MapIo) {
  test::TempDir dir;
  expectExactly<MapFileError>([&] { grid::mapFormatFromPath("map.xyz"); }, "mapFormatFromPath");
  expectExactly<MapFileError>([&] { grid::loadMap(dir / "missing.vdb"); }, "loadMap");
  expectExactly<MapFileError>([&] { grid::saveMap(smallMap(), dir / "no" / "such" / "folder.vdb"); }, "saveMap");
  OccupancyMap far;
  far.setLogOdds({40000, 0, 0}, 1.0f);
  expectExactly<MapFileError>([&] { grid::saveMap(far, dir / "far.ot"); }, "saveMap: key range");
}

TEST(Errors, HugePages) {
  EXPECT_THROW(grid::HugePageAllocator<double>().allocate(std::numeric_limits<std::size_t>::max() / 4), std::bad_alloc);
}

// --- kernels ---------------------------------------------------------------------------------

TEST(Errors, Kernels) {
  const kernels::VoxelLattice lattice(0.01);
  std::vector<kernels::RaySums> out(2);
  const std::vector<Eigen::Vector3f> ends = {Eigen::Vector3f(0.3f, 0, 0)};
  expectExactly<InvalidArgument>(
      [&] { kernels::walkRays(Eigen::Vector3f::Zero(), ends, lattice, kernels::SnapshotView{}, kernels::Isa::Scalar, out); },
      "walkRays");
  const kernels::DenseBox box = kernels::DenseBox::around({0, 0, 0}, {40, 8, 8});
  const std::vector<Eigen::Vector3f> origins = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
  const std::vector<Eigen::Vector3f> three_ends = {ends[0], ends[0], ends[0]};
  expectExactly<InvalidArgument>(
      [&] { kernels::markRays(origins, three_ends, lattice, box, kernels::MarkSpec{}, {}, kernels::Isa::Scalar); },
      "markRays");
  expectExactly<InvalidArgument>([] { kernels::metricValue(kernels::ViewSums{}, kernels::Metric::Random); },
                                 "metricValue");
}

// --- sensor ----------------------------------------------------------------------------------

TEST(Errors, CameraAndRaySets) {
  sensor::PinholeCamera camera;
  camera.fx = 0.0;
  expectExactly<InvalidArgument>([&] { camera.validate(); }, "PinholeCamera::validate");
  expectExactly<InvalidArgument>([] { sensor::PixelSampling{0, 1.0}.validate(); }, "PixelSampling::validate");
  expectExactly<InvalidArgument>([] { sensor::PixelSampling::fromName("sparse"); }, "PixelSampling::fromName");
  expectExactly<InvalidArgument>([&] { sensor::pixelRays(camera, sensor::PixelSampling::full()); }, "pixelRays");
}

TEST(Errors, DepthCameraAndScene) {
  sensor::DepthCameraConfig config;
  config.max_range_m = -1.0;
  expectExactly<InvalidArgument>([&] { sensor::DepthCamera{config}; }, "DepthCamera()");
  expectExactly<InvalidArgument>([] { sensor::RayScene{sensor::TriangleMesh{}}; }, "RayScene(): no triangles");
  sensor::TriangleMesh bad = test::boxMesh({0, 0, 0}, {1, 1, 1});
  bad.triangles[0].x() = 99;
  expectExactly<InvalidArgument>([&] { sensor::RayScene{bad}; }, "RayScene(): index");
  const sensor::RayScene scene(test::boxMesh({0, 0, 0}, {1, 1, 1}));
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2.0;
  expectExactly<InvalidArgument>([&] { sensor::DepthCamera().render(scene, scaled); }, "DepthCamera::render");
}

TEST(Errors, MeshesAndSurfaces) {
  test::TempDir dir;
  expectExactly<MeshFileError>([&] { sensor::loadMesh(dir / "missing.off"); }, "loadMesh");
  expectExactly<MeshFileError>([&] { sensor::resolveModel("not-a-model", {dir.path()}); }, "resolveModel");
  sensor::TriangleMesh empty;
  expectExactly<InvalidArgument>([&] { sensor::normalizeMesh(empty); }, "normalizeMesh");
  sensor::TriangleMesh flat;
  flat.vertices = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()};
  flat.triangles = {Eigen::Vector3i(0, 1, 2)};
  expectExactly<InvalidArgument>([&] { sensor::sampleSurface(flat, 10, 0); }, "sampleSurface");
}

TEST(Errors, PointClouds) {
  test::TempDir dir;
  expectExactly<CloudFileError>([&] { sensor::readPlyCloud(dir / "missing.ply"); }, "readPlyCloud");
  expectExactly<CloudFileError>([&] { sensor::writePlyCloud(dir / "no" / "folder.ply", {}); }, "writePlyCloud");
}

// --- planner ---------------------------------------------------------------------------------

TEST(Errors, Viewspaces) {
  test::TempDir dir;
  expectExactly<InvalidArgument>([] { planner::lookAt({0, 0, 1}, {0, 0, 0}); }, "lookAt: straight down");
  expectExactly<InvalidArgument>([] { planner::fibonacciSphere(0, 0.6, Eigen::Vector3d::Zero()); }, "fibonacciSphere");
  expectExactly<InvalidArgument>(
      [] { planner::fibonacciSphere(planner::kMaxFibonacciViews + 1, 0.6, Eigen::Vector3d::Zero()); },
      "fibonacciSphere: too many views");
  std::ofstream(dir / "short.txt") << "2\n0 0 0 0 0 0 1\n";
  expectExactly<ViewFileError>([&] { planner::loadViews(dir / "short.txt"); }, "loadViews");
  expectExactly<ViewFileError>([&] { planner::saveViews(dir / "no" / "folder.txt", planner::dome48()); }, "saveViews");
  expectExactly<InvalidArgument>([] { planner::viewFromPose(0, 0, 0, 0, 0, 0, 0); }, "viewFromPose: zero quaternion");
  expectExactly<InvalidArgument>([] { planner::viewFromPose(kNaN, 0, 0, 0, 0, 0, 1); }, "viewFromPose: NaN");
}

TEST(Errors, UtilityAndScores) {
  expectExactly<InvalidArgument>([] { planner::utilities(std::vector<double>{1.0}, std::vector<double>{}, 0.0); },
                                 "utilities");
  expectExactly<InvalidArgument>([] { planner::parseMetricSum("pc+"); }, "parseMetricSum");
  expectExactly<InvalidArgument>([] { planner::weightingFromName("sum"); }, "weightingFromName");
  const std::vector<planner::MetricWeight> two(2);
  expectExactly<InvalidArgument>([&] { planner::combinedGains(std::vector<double>{1.0}, two, planner::Weighting::Raw); },
                                 "combinedGains");
  expectExactly<InvalidArgument>([] { planner::SurfaceCoverage(std::vector<Eigen::Vector3f>{}); }, "SurfaceCoverage()");
  expectExactly<InvalidArgument>([] { planner::SurfaceCoverage(std::shared_ptr<const planner::GroundTruth>{}); },
                                 "SurfaceCoverage(): no ground truth");
  expectExactly<InvalidArgument>([] { planner::areaUnderCurve(std::vector<double>{1.0}, 0.0, 0.0); }, "areaUnderCurve");
}

TEST(Errors, ReconstructionAndWorkloads) {
  planner::ReconstructionConfig config;
  config.metrics[0].weight = 0.0;
  expectExactly<InvalidArgument>([&] { config.validate(); }, "ReconstructionConfig::validate");
  const sensor::TriangleMesh box = test::boxMesh({-0.1f, -0.1f, 0.0f}, {0.1f, 0.1f, 0.2f});
  expectExactly<InvalidArgument>([&] { planner::reconstruct(box, {}, planner::ReconstructionConfig{}); },
                                 "reconstruct: no view");
  test::TempDir dir;
  expectExactly<InvalidArgument>([&] { planner::makeWorkload("bunny-4", {dir.path()}); }, "makeWorkload: name");
  expectExactly<MeshFileError>([&] { planner::makeWorkload("bunny-3", {dir.path()}); }, "makeWorkload: no model");
}

}  // namespace
}  // namespace nbv
