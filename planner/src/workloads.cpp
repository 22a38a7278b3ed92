#include "nbv/planner/workloads.hpp"

#include "nbv/grid/map_io.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"

#include "nbv/errors.hpp"

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <random>

namespace nbv::planner {

namespace {

using Eigen::Vector3d;
using Eigen::Vector3f;
namespace fs = std::filesystem;

/// Uniform numbers in [lo, hi) from a seeded 64-bit Mersenne Twister, from its raw bits (the
/// standard distributions may differ between standard libraries; these do not).
class Draws {
 public:
  explicit Draws(std::uint64_t seed) : engine_(seed) {}
  double operator()(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  }

 private:
  std::mt19937_64 engine_;
};

void addBox(sensor::TriangleMesh& scene, const Vector3d& lo, const Vector3d& hi) {
  sensor::appendMesh(scene, sensor::boxMesh(lo.cast<float>(), hi.cast<float>()));
}

/// A standard model placed with its largest side `side_m` and its lowest point at `base`.
sensor::TriangleMesh placedModel(const std::string& name, const std::vector<fs::path>& models, double side_m,
                                 const Vector3d& base) {
  sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel(name, models));
  sensor::Placement placement;
  placement.up = sensor::upAxisFor(name, "auto");
  placement.largest_side_m = side_m;
  sensor::normalizeMesh(mesh, placement);
  for (Vector3f& v : mesh.vertices) v += base.cast<float>();
  return mesh;
}

/// The scan of `camera` from `T_world_camera`, handed to `each`.
void scanFrom(const sensor::DepthCamera& camera, const sensor::RayScene& scene, const Eigen::Isometry3d& T_world_camera,
              const EachScan& each) {
  each({camera.render(scene, T_world_camera).points_world, T_world_camera.translation().cast<float>()});
}

/// A map configuration: the defaults, with this resolution and range.
grid::MapConfig mapConfig(double resolution_m, double max_range_m) {
  grid::MapConfig config;
  config.resolution = resolution_m;
  config.max_range = max_range_m;
  return config;
}

void bunny3Scans(const std::vector<fs::path>& models, std::uint64_t /*seed: the scans are ideal*/, const EachScan& each) {
  sensor::TriangleMesh mesh = sensor::loadMesh(sensor::resolveModel("bunny", models));
  sensor::normalizeMesh(mesh);  // SEMANTICS.md "Simulation and evaluation"
  const sensor::RayScene scene(mesh);
  const std::vector<View> dome = dome48();
  for (const std::size_t index : {0u, 16u, 33u}) scanFrom(sensor::DepthCamera(), scene, dome[index].T_world_camera, each);
}

Workload bunny3(const std::string& name, grid::OccupancyMap scanned) {
  return {name, std::move(scanned), dome48()};
}

// ---------------------------------------------------------------------------------- room --

/// room-2cm's interior: [-3, 3] x [-2.5, 2.5] x [0, 2.7] m, walls, floor and ceiling 10 cm thick.
constexpr double kRoomX = 3.0, kRoomY = 2.5, kRoomZ = 2.7, kRoomWall = 0.1;
/// The table's top centre and half extents; the object stands on it.
const Vector3d kTableCentre(0.8, 0.4, 0.76);
constexpr double kTableHalfX = 0.6, kTableHalfY = 0.4;

sensor::TriangleMesh roomScene(const std::vector<fs::path>& models, Draws& draw) {
  sensor::TriangleMesh scene;
  const double w = kRoomWall;
  addBox(scene, {-kRoomX - w, -kRoomY - w, -w}, {kRoomX + w, kRoomY + w, 0.0});             // floor
  addBox(scene, {-kRoomX - w, -kRoomY - w, kRoomZ}, {kRoomX + w, kRoomY + w, kRoomZ + w});  // ceiling
  addBox(scene, {-kRoomX - w, -kRoomY, 0.0}, {-kRoomX, kRoomY, kRoomZ});
  addBox(scene, {kRoomX, -kRoomY, 0.0}, {kRoomX + w, kRoomY, kRoomZ});
  addBox(scene, {-kRoomX - w, -kRoomY - w, 0.0}, {kRoomX + w, -kRoomY, kRoomZ});
  addBox(scene, {-kRoomX - w, kRoomY, 0.0}, {kRoomX + w, kRoomY + w, kRoomZ});
  // The table: a top on four legs, and the bunny on it.
  const Vector3d top_lo = kTableCentre - Vector3d(kTableHalfX, kTableHalfY, 0.04);
  const Vector3d top_hi = kTableCentre + Vector3d(kTableHalfX, kTableHalfY, 0.0);
  addBox(scene, top_lo, top_hi);
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      const Vector3d leg(kTableCentre.x() + sx * (kTableHalfX - 0.05), kTableCentre.y() + sy * (kTableHalfY - 0.05), 0.0);
      addBox(scene, leg - Vector3d(0.025, 0.025, 0.0), leg + Vector3d(0.025, 0.025, top_lo.z()));
    }
  }
  sensor::appendMesh(scene, placedModel("bunny", models, 0.3, kTableCentre));
  // Furniture along the walls: a cabinet, a sofa with its back, a bookshelf.
  addBox(scene, {2.5, -2.3, 0.0}, {3.0, -1.1, 1.9});
  addBox(scene, {-2.9, -1.0, 0.0}, {-2.0, 1.0, 0.45});
  addBox(scene, {-3.0, -1.0, 0.0}, {-2.8, 1.0, 0.9});
  addBox(scene, {-1.5, 2.1, 0.0}, {0.5, 2.5, 2.0});
  // Boxes on the floor at drawn places, clear of the table and of the middle of the room
  // (where the candidates are).
  for (int placed = 0; placed < 5;) {
    const Vector3d size(draw(0.3, 0.7), draw(0.3, 0.7), draw(0.3, 0.9));
    const Vector3d lo(draw(-2.4, 2.4 - size.x()), draw(-2.0, 2.0 - size.y()), 0.0);
    const Eigen::Vector2d nearest = Eigen::Vector2d::Zero().cwiseMax(lo.head<2>()).cwiseMin((lo + size).head<2>());
    const bool clear = lo.x() > kTableCentre.x() + kTableHalfX + 0.2 || lo.x() + size.x() < kTableCentre.x() - kTableHalfX - 0.2 ||
                       lo.y() > kTableCentre.y() + kTableHalfY + 0.2 || lo.y() + size.y() < kTableCentre.y() - kTableHalfY - 0.2;
    if (!clear || nearest.norm() < 1.3) continue;
    addBox(scene, lo, lo + size);
    ++placed;
  }
  return scene;
}

void room2cmScans(const std::vector<fs::path>& models, std::uint64_t seed, const EachScan& each) {
  Draws draw(seed);
  const sensor::RayScene scene(roomScene(models, draw));
  // A dataset-like camera (ICL-NUIM's intrinsics, a flipped y axis), Kinect-like axial noise,
  // 3 % of the pixels and one 40-pixel square per frame lost; it sees to 5 m, the map keeps 4.
  sensor::DepthCameraConfig camera;
  camera.camera = {640, 480, 481.2, -480.0, 319.5, 239.5};
  camera.max_range_m = 5.0;
  camera.noise = {sensor::DepthNoise::Kind::AxialGaussian, 0.0012, 0.0019, 0};
  camera.holes = {0.03, 1, 40, 0};
  // 24 frames on a loop around the room's middle, every third looking at the object, the
  // others at drawn points of the walls and furniture ahead.
  constexpr int kFrames = 24;
  for (int f = 0; f < kFrames; ++f) {
    const double angle = 2.0 * M_PI * f / kFrames;
    const Vector3d position(1.7 * std::cos(angle), 1.3 * std::sin(angle), 1.4 + 0.2 * std::sin(2.0 * angle));
    const double heading = angle + draw(-1.0, 1.0);
    const Vector3d target = f % 3 == 0 ? kTableCentre + Vector3d(0.0, 0.0, 0.12)
                                       : Vector3d(2.9 * std::cos(heading), 2.4 * std::sin(heading), draw(0.3, 1.8));
    const Eigen::Isometry3d T_world_camera = lookAt(position, target).T_world_camera;
    camera.noise.seed = seed * 1000 + static_cast<std::uint64_t>(f);
    camera.holes.seed = seed * 1000 + static_cast<std::uint64_t>(f) + 500;
    scanFrom(sensor::DepthCamera(camera), scene, T_world_camera, each);
  }
}

Workload room2cm(const std::string& name, grid::OccupancyMap scanned) {
  return {name, std::move(scanned), fibonacciSphere(48, 1.0, Vector3d(0.0, 0.0, 1.5)), 4.0};
}

// ------------------------------------------------------------------------------ building --

/// The building's floor: [-16, 16] x [-8, 8] x [0, 3] m inside 15 cm walls; a corridor along x
/// (|y| < 1) and one along y (|x| < 1); on each side of them 4 rooms in a row, each with a door
/// onto the long corridor.
constexpr double kFloorX = 16.0, kFloorY = 8.0, kFloorZ = 3.0, kWall = 0.15, kCorridor = 1.0;
constexpr double kDoorWidth = 1.0, kDoorHeight = 2.1;
constexpr int kRoomsPerRow = 4;

/// A room: its x extent and its side of the long corridor (+1: y > 0).
struct FloorRoom {
  double x0, x1;
  double side;
  double centreY() const { return side * 0.5 * (kCorridor + kWall + kFloorY); }
};

std::vector<FloorRoom> floorRooms() {
  std::vector<FloorRoom> rooms;
  const double row = (kFloorX - kCorridor - kWall) / kRoomsPerRow;
  for (const double side : {-1.0, 1.0}) {
    for (const double half : {-1.0, 1.0}) {  // west and east of the cross corridor
      for (int k = 0; k < kRoomsPerRow; ++k) {
        const double a = kCorridor + kWall + k * row, b = a + row;
        rooms.push_back(half > 0 ? FloorRoom{a, b, side} : FloorRoom{-b, -a, side});
      }
    }
  }
  return rooms;
}

sensor::TriangleMesh buildingScene(Draws& draw) {
  sensor::TriangleMesh scene;
  const double X = kFloorX + kWall, Y = kFloorY + kWall;
  addBox(scene, {-X, -Y, -kWall}, {X, Y, 0.0});
  addBox(scene, {-X, -Y, kFloorZ}, {X, Y, kFloorZ + kWall});
  addBox(scene, {-X, -Y, 0.0}, {-kFloorX, Y, kFloorZ});
  addBox(scene, {kFloorX, -Y, 0.0}, {X, Y, kFloorZ});
  addBox(scene, {-X, -Y, 0.0}, {X, -kFloorY, kFloorZ});
  addBox(scene, {-X, kFloorY, 0.0}, {X, Y, kFloorZ});
  const double wall_lo = kCorridor, wall_hi = kCorridor + kWall;  // |y| of the long corridor's walls
  for (const FloorRoom& room : floorRooms()) {
    const double y0 = room.side > 0 ? wall_lo : -wall_hi, y1 = room.side > 0 ? wall_hi : -wall_lo;
    // The corridor wall of the room, with its door at a drawn place, a lintel above it.
    const double door = draw(room.x0 + 0.3, room.x1 - 0.3 - kDoorWidth);
    addBox(scene, {room.x0, y0, 0.0}, {door, y1, kFloorZ});
    addBox(scene, {door + kDoorWidth, y0, 0.0}, {room.x1, y1, kFloorZ});
    addBox(scene, {door, y0, kDoorHeight}, {door + kDoorWidth, y1, kFloorZ});
    // A desk by the far wall and a cabinet at a drawn place.
    const double desk = draw(room.x0 + 0.3, room.x1 - 1.7);
    const double desk_y = room.side > 0 ? kFloorY - 0.75 : -kFloorY;
    addBox(scene, {desk, desk_y, 0.0}, {desk + 1.4, desk_y + 0.75, draw(0.7, 0.8)});
    const double cabinet = draw(room.x0 + 0.2, room.x1 - 1.2);
    const double cabinet_y = room.centreY() + room.side * draw(1.2, 2.0);  // clear of the scan place
    addBox(scene, {cabinet, cabinet_y - 0.25, 0.0}, {cabinet + 1.0, cabinet_y + 0.25, draw(1.2, 2.0)});
  }
  // The walls across each row of rooms: the cross corridor's (|x| = 1) and those between rooms.
  const double row = (kFloorX - kCorridor - kWall) / kRoomsPerRow;
  for (const double side : {-1.0, 1.0}) {
    const double ya = side * wall_hi, yb = side * kFloorY;
    for (const double half : {-1.0, 1.0}) {
      for (int k = 0; k < kRoomsPerRow; ++k) {
        const double x = half * (kCorridor + (k == 0 ? 0.5 * kWall : kWall + k * row));
        addBox(scene, {x - 0.5 * kWall, std::min(ya, yb), 0.0}, {x + 0.5 * kWall, std::max(ya, yb), kFloorZ});
      }
    }
  }
  return scene;
}

/// The places of the scanner: along the long corridor every metre, along the cross corridor,
/// and one in the middle of each room; 1.2 m above the floor.
std::vector<Vector3d> scanPlaces() {
  std::vector<Vector3d> places;
  for (int i = -15; i <= 15; ++i) places.emplace_back(i, 0.0, 1.2);
  for (int j = 2; j <= 8; ++j) {
    for (const double side : {-1.0, 1.0}) places.emplace_back(0.0, side * (j - 0.5), 1.2);
  }
  for (const FloorRoom& room : floorRooms()) places.emplace_back(0.5 * (room.x0 + room.x1), room.centreY(), 1.2);
  return places;
}

/// A file name no other call of this process or another one uses.
fs::path scratchFile(const std::string& extension) {
  static std::atomic<unsigned> counter{0};
  return fs::temp_directory_path() /
         ("nbv-workload-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + extension);
}

void buildingScans(std::uint64_t seed, const EachScan& each) {
  Draws draw(seed);
  const sensor::RayScene scene(buildingScene(draw));
  // A laser-like rig: four cameras a quarter turn apart (each 90 degrees across, 74 up and
  // down), 1 cm of noise, 1 % of the returns lost, 10 m of range.
  sensor::DepthCameraConfig camera;
  camera.camera = {240, 320, 160.0, 160.0, 119.5, 159.5};
  camera.max_range_m = 10.0;
  camera.noise = {sensor::DepthNoise::Kind::AxialGaussian, 0.01, 0.0, 0};
  camera.holes = {0.01, 0, 1, 0};
  const std::vector<Vector3d> places = scanPlaces();
  for (std::size_t p = 0; p < places.size(); ++p) {
    for (int q = 0; q < 4; ++q) {
      const double heading = 0.5 * M_PI * q;
      const Eigen::Isometry3d T_world_camera =
          lookAt(places[p], places[p] + Vector3d(std::cos(heading), std::sin(heading), 0.0)).T_world_camera;
      const std::uint64_t frame = seed * 100000 + 4 * p + static_cast<std::uint64_t>(q);
      camera.noise.seed = frame;
      camera.holes.seed = frame + 50000;
      scanFrom(sensor::DepthCamera(camera), scene, T_world_camera, each);
    }
  }
}

Workload building(const std::string& name, grid::OccupancyMap scanned) {
  // As OctoMap's binary files give it: every voxel at a clamp, no marks.
  const fs::path file = scratchFile(".bt");
  Workload workload{name, grid::OccupancyMap(scanned.config()), {}, 6.0};
  try {
    grid::saveMap(scanned, file, grid::MapFormat::OctomapBt);
    workload.map = grid::loadMap(file, grid::MapFormat::OctomapBt, scanned.config());
  } catch (...) {
    std::error_code ignored;
    fs::remove(file, ignored);
    throw;
  }
  std::error_code ignored;
  fs::remove(file, ignored);
  // Candidates along the corridors, 1.5 m up, eight headings each, looking slightly down.
  std::vector<Vector3d> positions;
  for (int i = 0; i < 33; ++i) positions.emplace_back(-15.5 + i * (31.0 / 32.0), 0.0, 1.5);
  for (int j = 0; j < 8; ++j) {
    for (const double side : {-1.0, 1.0}) positions.emplace_back(0.0, side * (1.5 + j * 0.875), 1.5);
  }
  for (const Vector3d& position : positions) {
    for (int k = 0; k < 8; ++k) {
      const double heading = 0.25 * M_PI * k;
      workload.candidates.push_back(lookAt(position, position + Vector3d(std::cos(heading), std::sin(heading), -0.18)));
    }
  }
  return workload;
}

}  // namespace

const std::vector<WorkloadRow> kWorkloadTable = {
    {"bunny-3", "the bunny at 1 cm after 3 ideal scans, the 48 dome views", grid::MapConfig{}, bunny3Scans, bunny3},
    {"room-2cm", "a furnished room at 2 cm from 24 noisy depth frames, 48 views inside it, 4 m rays", mapConfig(0.02, 4.0),
     room2cmScans, room2cm},
    {"building-8cm", "a 32 x 16 m floor at 8 cm read back from .bt, 392 views along its corridors, 6 m rays",
     mapConfig(0.08, 10.0), [](const std::vector<fs::path>&, std::uint64_t seed, const EachScan& each) { buildingScans(seed, each); },
     building},
    {"building-5cm", "the same floor at 5 cm", mapConfig(0.05, 10.0),
     [](const std::vector<fs::path>&, std::uint64_t seed, const EachScan& each) { buildingScans(seed, each); }, building},
};

std::vector<std::string> workloadNames() {
  std::vector<std::string> names;
  for (const WorkloadRow& row : kWorkloadTable) names.emplace_back(row.name);
  return names;
}

std::string workloadNamesText() {
  std::string text;
  for (const WorkloadRow& row : kWorkloadTable) text += (text.empty() ? "" : ", ") + std::string(row.name);
  return text;
}

const WorkloadRow& workloadRow(const std::string& name) {
  for (const WorkloadRow& row : kWorkloadTable) {
    if (row.name == name) return row;
  }
  throw InvalidArgument("unknown workload '" + name + "' (known: " + workloadNamesText() + ")");
}

Workload makeWorkload(const std::string& name, const std::vector<fs::path>& models, std::uint64_t seed) {
  const WorkloadRow& row = workloadRow(name);
  grid::OccupancyMap map(row.config);
  row.scans(models, seed, [&map](const WorkloadScan& scan) { map.integrate(scan.points_world, scan.origin_world); });
  return row.finish(name, std::move(map));
}

}  // namespace nbv::planner
