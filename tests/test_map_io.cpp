// Map files: .vdb round trip, OctoMap .ot/.bt export and import, and bad files.
#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"

#include "expect_file_error.hpp"
#include "octomap_compare.hpp"
#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <openvdb/io/File.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

namespace {

using nbv::MapFileError;
using nbv::grid::OccupancyMap;
namespace fs = std::filesystem;

OccupancyMap sphereMap(const OccupancyMap::Config& config = {}) {
  OccupancyMap map(config);
  const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  for (const Eigen::Vector3d& position : {Eigen::Vector3d(0.6, 0.0, 0.15), Eigen::Vector3d(-0.3, 0.5, 0.5)}) {
    map.integrate(nbv::test::idealScan(sphere, nbv::test::lookAt(position, sphere.centre), 6),
                  position.cast<float>());
  }
  return map;
}

void expectSameVoxels(const OccupancyMap& a, const OccupancyMap& b) {
  const auto va = a.measuredVoxels();
  const auto vb = b.measuredVoxels();
  ASSERT_EQ(va.size(), vb.size());
  for (std::size_t i = 0; i < va.size(); ++i) {
    ASSERT_EQ(va[i].ijk, vb[i].ijk);
    ASSERT_EQ(va[i].log_odds, vb[i].log_odds);
  }
}

std::string readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

using nbv::test::writeBytes;

/// OctoMap's key of nbv's voxel (x, y, z).
octomap::OcTreeKey key(int x, int y, int z) {
  return {static_cast<octomap::key_type>(32768 + x), static_cast<octomap::key_type>(32768 + y),
          static_cast<octomap::key_type>(32768 + z)};
}

TEST(MapIo, VdbRoundTripKeepsVoxelsMarksAndConfig) {
  nbv::test::TempDir dir;
  OccupancyMap::Config config;
  config.p_hit = 0.75;
  config.proximity_range = 0.2;
  const OccupancyMap map = sphereMap(config);
  ASSERT_GT(map.markedCount(), 0u);
  nbv::grid::saveMap(map, dir / "map.vdb");
  const OccupancyMap loaded = nbv::grid::loadMap(dir / "map.vdb");
  expectSameVoxels(map, loaded);
  const auto ma = map.proximityMarks();
  const auto mb = loaded.proximityMarks();
  ASSERT_EQ(ma.size(), mb.size());
  for (std::size_t i = 0; i < ma.size(); ++i) {
    ASSERT_EQ(ma[i].ijk, mb[i].ijk);
    ASSERT_EQ(ma[i].distance, mb[i].distance);
  }
  EXPECT_EQ(loaded.config().p_hit, 0.75);
  EXPECT_EQ(loaded.config().proximity_range, 0.2);
  EXPECT_EQ(loaded.config().resolution, 0.01);
}

TEST(MapIo, VdbKeepsEveryConfigurationFieldAndReadsALaterFieldsDefaultFromAnOlderFile) {
  nbv::test::TempDir dir;
  OccupancyMap::Config config;
  // Every field off its default by a value each check takes.
  config.resolution = 0.02;
  config.p_hit = 0.72;
  config.p_miss = 0.41;
  config.clamp_min = 0.11;
  config.clamp_max = 0.96;
  config.max_range = 2.5;
  config.proximity_range = 0.25;
  config.occupied_threshold = 0.79;
  config.free_threshold = 0.21;
  config.min_range = 0.05;
  const OccupancyMap::Config defaults;
  for (const nbv::grid::MapConfigField& field : nbv::grid::mapConfigFields()) {
    ASSERT_NE(config.*field.member, defaults.*field.member) << field.name << ": the test must change every field";
  }
  nbv::grid::saveMap(OccupancyMap(config), dir / "map.vdb");
  const OccupancyMap::Config loaded = nbv::grid::loadMap(dir / "map.vdb").config();
  for (const nbv::grid::MapConfigField& field : nbv::grid::mapConfigFields()) {
    EXPECT_EQ(loaded.*field.member, config.*field.member) << field.name;
  }

  // A file of the first version holds no later field: it reads as the default; a first-version
  // field missing is an error naming it.
  {
    openvdb::io::File file((dir / "map.vdb").string());
    file.open();
    openvdb::GridPtrVecPtr grids = file.getGrids();
    file.close();
    for (std::size_t i = nbv::grid::kFirstMapConfigFields; i < nbv::grid::mapConfigFields().size(); ++i) {
      (*grids)[0]->removeMeta(std::string("nbv_") + nbv::grid::mapConfigFields()[i].name);
    }
    openvdb::io::File((dir / "old.vdb").string()).write(*grids);
    (*grids)[0]->removeMeta("nbv_p_miss");
    openvdb::io::File((dir / "broken.vdb").string()).write(*grids);
  }
  EXPECT_EQ(nbv::grid::loadMap(dir / "old.vdb").config().min_range, defaults.min_range);
  EXPECT_EQ(nbv::grid::loadMap(dir / "old.vdb").config().p_hit, config.p_hit);
  nbv::test::expectFileError<MapFileError>(dir / "broken.vdb", [](const fs::path& p) { nbv::grid::loadMap(p); },
                                           "missing metadata 'nbv_p_miss'");
}

TEST(MapIo, OtExportReadBackByLiboctomapIsEqual) {
  nbv::test::TempDir dir;
  const OccupancyMap map = sphereMap();
  nbv::grid::saveMap(map, dir / "map.ot");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read((dir / "map.ot").string()));
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  EXPECT_EQ(tree->getResolution(), 0.01);
  nbv::test::expectMapEqualsTree(map, *tree, 0.0);
}

TEST(MapIo, OtImportOfALiboctomapTreeIsEqual) {
  nbv::test::TempDir dir;
  octomap::OcTree tree(0.02);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> coord(-0.5f, 0.5f);
  octomap::Pointcloud cloud;
  for (int i = 0; i < 2000; ++i) cloud.push_back(coord(rng), coord(rng), coord(rng));
  tree.insertPointCloud(cloud, octomap::point3d(0.01f, 0.0f, 0.0f));
  tree.insertPointCloud(cloud, octomap::point3d(0.3f, 0.2f, 0.1f));
  ASSERT_TRUE(tree.write((dir / "tree.ot").string()));
  const OccupancyMap map = nbv::grid::loadMap(dir / "tree.ot");
  EXPECT_EQ(map.config().resolution, 0.02);
  nbv::test::expectMapEqualsTree(map, tree, 0.0);
}

TEST(MapIo, BtKeepsOnlyTheMaximumLikelihoodClass) {
  nbv::test::TempDir dir;
  const OccupancyMap map = sphereMap();
  nbv::grid::saveMap(map, dir / "map.bt");
  const OccupancyMap loaded = nbv::grid::loadMap(dir / "map.bt");
  const auto original = map.measuredVoxels();
  const auto read = loaded.measuredVoxels();
  ASSERT_EQ(original.size(), read.size());
  const float upper = OccupancyMap::logOddsOf(0.97);
  const float lower = OccupancyMap::logOddsOf(0.12);
  for (std::size_t i = 0; i < read.size(); ++i) {
    ASSERT_EQ(original[i].ijk, read[i].ijk);
    ASSERT_EQ(read[i].log_odds, original[i].log_odds >= 0.0f ? upper : lower);
  }
  EXPECT_EQ(loaded.markedCount(), 0u);  // .bt cannot carry proximity marks
}

std::string fileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(MapIo, BtExportIsLiboctomapsBytesAndPrintsNothing) {
  nbv::test::TempDir dir;
  const OccupancyMap map = sphereMap();
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  nbv::grid::saveMap(map, dir / "nbv.bt");
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");  // Debian's liboctomap says " done." here
  // The same tree written by liboctomap itself (it prints, so this is captured too).
  nbv::grid::saveMap(map, dir / "map.ot");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read((dir / "map.ot").string()));
  auto* tree = dynamic_cast<octomap::OcTree*>(read.get());
  ASSERT_NE(tree, nullptr);
  testing::internal::CaptureStderr();
  ASSERT_TRUE(tree->writeBinary((dir / "octomap.bt").string()));
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(fileBytes(dir / "nbv.bt"), fileBytes(dir / "octomap.bt"));
}

TEST(MapIo, EmptyMapRoundTripsInEveryFormat) {
  nbv::test::TempDir dir;
  const OccupancyMap empty;
  for (const char* name : {"e.vdb", "e.ot", "e.bt"}) {
    nbv::grid::saveMap(empty, dir / name);
    EXPECT_EQ(nbv::grid::loadMap(dir / name).measuredCount(), 0u) << name;
  }
}

TEST(MapIo, UnknownExtensionIsRefused) {
  const auto format = [](const fs::path& p) { nbv::grid::mapFormatFromPath(p); };
  nbv::test::expectFileError<MapFileError>("map.xyz", format, "unknown map format '.xyz' (expected .vdb, .ot or .bt)");
  nbv::test::expectFileError<MapFileError>("map", format, "no extension to tell the map format by");
  nbv::test::expectFileError<MapFileError>("-", format, "no extension to tell the map format by");
  EXPECT_EQ(nbv::grid::mapFormatFromPath("A.VDB"), nbv::grid::MapFormat::Vdb);
}

/// Every bad variant of a good file must throw MapFileError naming the file.
void expectRefused(const fs::path& path) {
  nbv::test::expectFileError<MapFileError>(path, [](const fs::path& p) { nbv::grid::loadMap(p); });
}

class BadMapFiles : public ::testing::TestWithParam<const char*> {};

TEST_P(BadMapFiles, EmptyTruncatedGarbageMissingAndDirectoryAreRefused) {
  nbv::test::TempDir dir;
  const std::string ext = GetParam();
  const fs::path good = dir / ("good" + ext);
  nbv::grid::saveMap(sphereMap(), good);
  const std::string bytes = readBytes(good);
  ASSERT_GT(bytes.size(), 100u);

  expectRefused(dir / ("missing" + ext));
  fs::create_directory(dir / ("folder" + ext));
  expectRefused(dir / ("folder" + ext));
  writeBytes(dir / ("empty" + ext), "");
  expectRefused(dir / ("empty" + ext));
  // Truncated everywhere: every 41st byte through header and data, and one byte short. (A
  // truncated .vdb once made OpenVDB allocate 12 GB from an uninitialised length.)
  const fs::path cut = dir / ("cut" + ext);
  for (std::size_t length = 1; length < bytes.size(); length += 41) {
    writeBytes(cut, bytes.substr(0, length));
    expectRefused(cut);
  }
  writeBytes(cut, bytes.substr(0, bytes.size() - 1));
  expectRefused(cut);
  std::mt19937 rng(2);
  std::string garbage(4096, '\0');
  for (char& c : garbage) c = static_cast<char>(rng());
  writeBytes(dir / ("garbage" + ext), garbage);
  expectRefused(dir / ("garbage" + ext));
  // The right header followed by garbage.
  const std::size_t header_end = ext == ".vdb" ? 8 : bytes.find("data\n") + 5;
  writeBytes(dir / ("body" + ext), bytes.substr(0, header_end) + garbage);
  expectRefused(dir / ("body" + ext));
}

INSTANTIATE_TEST_SUITE_P(AllFormats, BadMapFiles, ::testing::Values(".vdb", ".ot", ".bt"));

TEST(MapIo, VdbBufferLengthsAreCheckedBeforeOpenVdbReadsThem) {
  // One voxel: its leaf stores 4 bytes of log-odds through blosc, behind the int64 length 20
  // (a 16-byte blosc header saying 4 bytes in 20, then the bytes). OpenVDB allocates a
  // positive length before reading it (fuzz_map's blosc_length.vdb), copies -length bytes
  // into the 4-byte buffer for a negative one, and blosc trusts its header: each must be
  // refused by name before OpenVDB reads the file.
  nbv::test::TempDir dir;
  OccupancyMap map;
  map.setLogOdds(nbv::grid::Index3(3, 4, 5), 0.85f);
  const fs::path good = dir / "one.vdb";
  nbv::grid::saveMap(map, good);
  EXPECT_EQ(nbv::grid::loadMap(good).measuredCount(), 1u);
  const std::string bytes = readBytes(good);
  auto int64At = [&bytes](std::size_t at) {
    std::int64_t v;
    std::memcpy(&v, bytes.data() + at, 8);
    return v;
  };
  auto int32At = [&bytes](std::size_t at) {
    std::int32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  std::size_t at = 0;
  for (std::size_t i = 0; i + 28 <= bytes.size(); ++i) {
    if (int64At(i) == 20 && int32At(i + 12) == 4 && int32At(i + 20) == 20) {
      ASSERT_EQ(at, 0u) << "two leaf buffers";
      at = i;
    }
  }
  ASSERT_NE(at, 0u);
  auto refused = [&](std::size_t offset, auto value, const std::string& name) {
    std::string bad = bytes;
    std::memcpy(bad.data() + offset, &value, sizeof value);
    const fs::path path = dir / (name + ".vdb");
    writeBytes(path, bad);
    nbv::test::expectFileError<MapFileError>(path, [](const fs::path& p) { nbv::grid::loadMap(p); }, "leaf values");
  };
  refused(at, std::int64_t{1} << 40, "terabyte");
  refused(at, std::int64_t{-4096}, "raw_longer_than_buffer");
  refused(at, std::int64_t{-8}, "raw_wrong_size");
  refused(at, std::int64_t{19}, "shorter_than_header_says");
  refused(at + 12, std::int32_t{4096}, "blosc_says_more_bytes");
}

TEST(MapIo, VdbMarkBeyondSixteenBitsIsRefusedByName) {
  // A file's marks are an Int32Grid; the map holds 16 bits, so a larger distance is named,
  // not cut. The one mark's value is patched in the saved bytes (blosc leaves 4 bytes as they are).
  nbv::test::TempDir dir;
  OccupancyMap map;
  map.setProximity(nbv::grid::Index3(3, -4, 5), 54321);
  const fs::path good = dir / "mark.vdb";
  nbv::grid::saveMap(map, good);
  EXPECT_EQ(nbv::grid::loadMap(good).proximity(nbv::grid::Index3(3, -4, 5)), 54321);
  std::string bytes = readBytes(good);
  const std::int32_t stored = 54321, patched = 70000;
  const std::string needle(reinterpret_cast<const char*>(&stored), sizeof stored);
  const std::size_t at = bytes.find(needle);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes.find(needle, at + 1), std::string::npos);
  std::memcpy(bytes.data() + at, &patched, sizeof patched);
  const fs::path bad = dir / "mark_70000.vdb";
  writeBytes(bad, bytes);
  nbv::test::expectFileError<MapFileError>(bad, [](const fs::path& p) { nbv::grid::loadMap(p); },
                                           "proximity mark 70000 at voxel (3, -4, 5)");
}

TEST(MapIo, OctomapTreeClaimingHugeVolumeIsRefusedBeforeAllocating) {
  nbv::test::TempDir dir;
  // A root whose children are all leaves covers 2^48 voxels in a few bytes.
  std::string ot = "# Octomap OcTree file\nid OcTree\nsize 9\nres 0.01\ndata\n";
  const float value = 1.0f;
  const char all_children = static_cast<char>(0xFF), none = 0;
  ot.append(reinterpret_cast<const char*>(&value), 4);
  ot.push_back(all_children);
  for (int i = 0; i < 8; ++i) {
    ot.append(reinterpret_cast<const char*>(&value), 4);
    ot.push_back(none);
  }
  writeBytes(dir / "huge.ot", ot);
  expectRefused(dir / "huge.ot");
}

TEST(MapIo, NonFiniteLogOddsInOtIsRefused) {
  nbv::test::TempDir dir;
  std::string ot = "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.01\ndata\n";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ot.append(reinterpret_cast<const char*>(&nan), 4);
  ot.push_back('\0');
  writeBytes(dir / "nan.ot", ot);
  expectRefused(dir / "nan.ot");
}

TEST(MapIo, APrunedTreeOfMillionsOfVoxelsLoadsAsTiles) {
  // A fuzzer's 310-byte .bt (tests/fuzz/findings): 134,639,936 free voxels in pruned nodes. The
  // map holds them as tiles (kilobytes), counts and bounds them, and writes them back as pruned
  // nodes and as .vdb tiles; a cap below what it needs refuses it before any voxel is set.
  nbv::test::TempDir dir;
  const fs::path file = fs::path(NBV_TEST_BAD_INPUTS_DIR) / ".." / "fuzz" / "findings" / "expands_to_many_voxels.bt";
  nbv::grid::MapLoadReport report;
  const OccupancyMap map = nbv::grid::loadMap(file, nbv::grid::MapLoadOptions{}, &report);
  EXPECT_EQ(report.tree_type, "OcTree");
  EXPECT_EQ(report.dropped, "");
  EXPECT_EQ(map.measuredCount(), 134639936u);
  EXPECT_EQ(map.freeCount(), map.measuredCount());
  EXPECT_LT(map.memoryBytes(), std::size_t{1} << 20);
  for (const char* name : {"copy.bt", "copy.ot", "copy.vdb"}) {
    nbv::grid::saveMap(map, dir / name);
    EXPECT_LT(fs::file_size(dir / name), 100000u) << name;
    const OccupancyMap read = nbv::grid::loadMap(dir / name);
    EXPECT_EQ(read.measuredCount(), map.measuredCount()) << name;
    EXPECT_EQ(read.freeCount(), map.freeCount()) << name;
    EXPECT_EQ(read.measuredBoundsIndex()->min(), map.measuredBoundsIndex()->min()) << name;
    EXPECT_EQ(read.measuredBoundsIndex()->max(), map.measuredBoundsIndex()->max()) << name;
  }
  nbv::grid::MapLoadOptions small;
  small.max_bytes = 4096;
  nbv::test::expectFileError<MapFileError>(file, [&](const fs::path& p) { nbv::grid::loadMap(p, small); },
                                           "more than the cap of 0.0 MB");
}

TEST(MapIo, PrunedOctomapFilesLoadVoxelForVoxelAsLiboctomapReadsThem) {
  // A free 2 x 2 x 1 m block at 5 cm (32,000 voxels) with a few occupied voxels, pruned by
  // liboctomap: nbv's map holds the pruned cubes as tiles, and every voxel reads what
  // liboctomap's tree says, in .ot (log-odds) and .bt (the clamps); a scan into it touches the
  // tiles it crosses like voxels.
  nbv::test::TempDir dir;
  octomap::OcTree tree(0.05);
  nbv::test::configureLikeMap(tree, OccupancyMap::Config{});
  for (int x = 0; x < 40; ++x) {
    for (int y = 0; y < 40; ++y) {
      for (int z = 0; z < 20; ++z) tree.updateNode(key(x, y, z), false, true);
    }
  }
  for (int i = 0; i < 5; ++i) tree.updateNode(key(3 * i, 7, 11), true, true);
  tree.updateInnerOccupancy();
  tree.prune();
  std::size_t pruned = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) pruned += it.getDepth() < 16 ? 1 : 0;
  ASSERT_GT(pruned, 10u);
  ASSERT_TRUE(tree.write((dir / "room.ot").string()));
  const OccupancyMap from_ot = nbv::grid::loadMap(dir / "room.ot");
  nbv::test::expectMapEqualsTree(from_ot, tree, 0.0);
  EXPECT_LT(from_ot.memoryBytes(), std::size_t{32000} * sizeof(float));  // tiles, not a leaf per 512 voxels
  octomap::OcTree written(tree);  // (writeBinary turns its tree into the maximum-likelihood one)
  testing::internal::CaptureStderr();
  ASSERT_TRUE(written.writeBinary((dir / "room.bt").string()));
  testing::internal::GetCapturedStderr();
  octomap::OcTree binary(0.05);
  nbv::test::configureLikeMap(binary, OccupancyMap::Config{});  // its clamps are the maximum-likelihood values
  ASSERT_TRUE(binary.readBinary((dir / "room.bt").string()));
  nbv::test::expectMapEqualsTree(nbv::grid::loadMap(dir / "room.bt"), binary, 0.0);
  // A scan through the tiles: the same voxels as liboctomap's update of its pruned tree.
  OccupancyMap scanned = from_ot;
  const std::vector<Eigen::Vector3f> points = {{1.9f, 1.2f, 0.4f}, {0.3f, 1.7f, 0.8f}, {1.0f, 0.05f, 0.2f}};
  scanned.integrate(points, Eigen::Vector3f(0.52f, 0.61f, 0.33f));
  octomap::Pointcloud cloud;
  for (const auto& p : points) cloud.push_back(p.x(), p.y(), p.z());
  tree.insertPointCloud(cloud, octomap::point3d(0.52f, 0.61f, 0.33f), scanned.config().max_range);
  nbv::test::expectMapEqualsTree(scanned, tree, 1e-6);
}

TEST(MapIo, ColorAndStampedTreesLoadSayingWhatIsDropped) {
  // OctoMap's coloured and time-stamped trees hold an OcTree's log-odds (a ColorOcTree's .ot
  // adds three colour bytes per node; an OcTreeStamped's files hold no stamps): read as
  // OcTrees, the colours said to be dropped.
  nbv::test::TempDir dir;
  octomap::ColorOcTree color(0.02);
  octomap::OcTreeStamped stamped(0.02);
  octomap::OcTree plain(0.02);
  for (octomap::AbstractOccupancyOcTree* t : std::initializer_list<octomap::AbstractOccupancyOcTree*>{&color, &stamped, &plain}) {
    nbv::test::configureLikeMap(*t, OccupancyMap::Config{});
  }
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> coord(-30, 30);
  for (int i = 0; i < 400; ++i) {
    const octomap::OcTreeKey at = key(coord(rng), coord(rng), coord(rng));
    const bool hit = i % 3 == 0;
    color.updateNode(at, hit, true);
    color.setNodeColor(at, 200, 10, static_cast<std::uint8_t>(i));
    stamped.updateNode(at, hit, true);
    plain.updateNode(at, hit, true);
  }
  color.updateInnerOccupancy();
  stamped.updateInnerOccupancy();
  plain.updateInnerOccupancy();
  ASSERT_TRUE(color.write((dir / "color.ot").string()));
  ASSERT_TRUE(stamped.write((dir / "stamped.ot").string()));
  octomap::ColorOcTree color_copy(color);  // (writeBinary turns its tree into the maximum-likelihood one)
  octomap::OcTreeStamped stamped_copy(stamped);
  testing::internal::CaptureStderr();
  ASSERT_TRUE(color_copy.writeBinary((dir / "color.bt").string()));
  ASSERT_TRUE(stamped_copy.writeBinary((dir / "stamped.bt").string()));
  testing::internal::GetCapturedStderr();
  for (const char* name : {"color.ot", "stamped.ot", "color.bt", "stamped.bt"}) {
    nbv::grid::MapLoadReport report;
    const OccupancyMap map = nbv::grid::loadMap(dir / name, nbv::grid::MapLoadOptions{}, &report);
    const bool is_color = std::string(name).starts_with("color");
    const bool binary = std::string(name).ends_with(".bt");
    EXPECT_EQ(report.tree_type, is_color ? "ColorOcTree" : "OcTreeStamped") << name;
    EXPECT_EQ(report.dropped, is_color && !binary ? "the colours of " + std::to_string(color.getNumLeafNodes()) + " nodes" : "")
        << name;
    if (binary) {
      octomap::OcTree read(0.02);
      nbv::test::configureLikeMap(read, OccupancyMap::Config{});
      testing::internal::CaptureStderr();
      ASSERT_TRUE(read.readBinary((dir / name).string()));
      testing::internal::GetCapturedStderr();
      nbv::test::expectMapEqualsTree(map, read, 0.0);
    } else {
      nbv::test::expectMapEqualsTree(map, plain, 0.0);  // the same log-odds as an OcTree of the same updates
    }
  }
}

TEST(MapIo, ACoverageTableOfAColorOctomapRunIsReproducedFromItsFiles) {
  // A published NBV run's files (psc0628/NBV-Simulation's example: per-view ColorOcTree maps,
  // a ColorOcTree of ground-truth samples, and per map a line "occupied entropy coverage
  // entropy-rate"): its coverage column is the number of voxels in the object's box with
  // occupancy above 0.65 over the number of ground-truth voxels. Small trees of that format are
  // written here with liboctomap as the run writes them (the box initialised at L = 0, scans
  // inserted, colours set), the column computed with liboctomap as the run computes it, and
  // nbv's maps of the files must give it.
  nbv::test::TempDir dir;
  const double resolution = 0.01, half = 0.1;  // the object's box: [-0.1, 0.1]^3
  octomap::ColorOcTree truth(resolution);
  std::mt19937 rng(3);
  std::normal_distribution<float> around(0.0f, 1.0f);
  std::vector<octomap::point3d> surface;
  for (int i = 0; i < 3000; ++i) {  // samples of a sphere of radius 6 cm
    octomap::point3d p(around(rng), around(rng), around(rng));
    p = p * static_cast<float>(0.06 / p.norm());
    surface.push_back(p);
    const octomap::OcTreeKey key = truth.coordToKey(p);
    if (truth.search(key) == nullptr) {
      truth.setNodeValue(key, truth.getProbHitLog(), true);
      truth.integrateNodeColor(key, 168, 168, 168);
    }
  }
  truth.updateInnerOccupancy();
  ASSERT_TRUE(truth.write((dir / "GT_sample.ot").string()));
  std::size_t truth_voxels = 0;
  for (auto it = truth.begin_leafs(), end = truth.end_leafs(); it != end; ++it) ++truth_voxels;
  octomap::ColorOcTree run(resolution);
  for (double x = -half; x <= half; x += resolution) {
    for (double y = -half; y <= half; y += resolution) {
      for (double z = -half; z <= half; z += resolution) run.setNodeValue(x, y, z, 0.0f, true);
    }
  }
  std::vector<double> coverage;  // the run's column, as its files say
  const octomap::point3d origins[] = {{0.4f, 0.0f, 0.1f}, {-0.1f, 0.4f, 0.2f}, {0.0f, -0.3f, -0.3f}};
  for (int view = 0; view < 3; ++view) {
    octomap::Pointcloud cloud;
    for (const auto& p : surface) {
      if ((p - origins[view]).norm() < origins[view].norm()) cloud.push_back(p);  // the near side
    }
    run.insertPointCloud(cloud, origins[view], -1, true, false);
    run.updateInnerOccupancy();
    ASSERT_TRUE(run.write((dir / ("octomap" + std::to_string(view) + ".ot")).string()));
    std::size_t occupied = 0;
    for (auto it = run.begin_leafs(), end = run.end_leafs(); it != end; ++it) {
      const octomap::point3d c = it.getCoordinate();
      const bool inside = std::abs(c.x()) <= half && std::abs(c.y()) <= half && std::abs(c.z()) <= half;
      if (inside && it->getOccupancy() > 0.65) ++occupied;
    }
    coverage.push_back(static_cast<double>(occupied) / static_cast<double>(truth_voxels));
  }
  ASSERT_GT(coverage.back(), coverage.front());
  // nbv, from the files alone.
  const OccupancyMap ground_truth = nbv::grid::loadMap(dir / "GT_sample.ot");
  ASSERT_EQ(ground_truth.measuredCount(), truth_voxels);
  for (int view = 0; view < 3; ++view) {
    nbv::grid::MapLoadReport report;
    const OccupancyMap map =
        nbv::grid::loadMap(dir / ("octomap" + std::to_string(view) + ".ot"), nbv::grid::MapLoadOptions{}, &report);
    EXPECT_EQ(report.tree_type, "ColorOcTree");
    EXPECT_TRUE(report.dropped.starts_with("the colours of ")) << report.dropped;
    std::size_t occupied = 0;
    for (const nbv::grid::MeasuredVoxel& v : map.measuredVoxels()) {
      const Eigen::Vector3d c = map.indexToWorld(v.ijk);
      if ((c.array().abs() <= half).all() && OccupancyMap::probabilityOf(v.log_odds) > 0.65) ++occupied;
    }
    EXPECT_EQ(static_cast<double>(occupied) / static_cast<double>(ground_truth.measuredCount()), coverage[view])
        << "view " << view;
  }
}

TEST(MapIo, VoxelsAtZeroLogOddsAreOccupiedAsLiboctomapSays) {
  // A box initialised at L = 0 (as a run's maps are) and voxels just below and above: OctoMap's
  // isNodeOccupied() is L >= 0, the count agrees with liboctomap's, and .bt keeps them occupied.
  nbv::test::TempDir dir;
  OccupancyMap map;
  octomap::OcTree tree(map.config().resolution);
  nbv::test::configureLikeMap(tree, map.config());
  const float values[] = {0.0f, -1e-6f, 1e-6f, 0.0f, -0.4f, 0.85f};
  for (int i = 0; i < 6; ++i) {
    map.setLogOdds({i, 0, 0}, values[i]);
    tree.setNodeValue(key(i, 0, 0), values[i]);
  }
  std::size_t liboctomap_occupied = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) liboctomap_occupied += tree.isNodeOccupied(*it) ? 1 : 0;
  EXPECT_EQ(liboctomap_occupied, 4u);
  EXPECT_EQ(map.octomapOccupiedCount(), liboctomap_occupied);
  nbv::grid::saveMap(map, dir / "zero.bt");
  const OccupancyMap read = nbv::grid::loadMap(dir / "zero.bt");
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(read.logOdds(nbv::grid::Index3(i, 0, 0)),
              OccupancyMap::logOddsOf(values[i] >= 0.0f ? 0.97 : 0.12)) << "voxel " << i;
  }
}

TEST(MapIo, ExportBeyondOctomapKeyRangeIsRefused) {
  nbv::test::TempDir dir;
  OccupancyMap map;
  map.setLogOdds({40000, 0, 0}, 1.0f);
  EXPECT_THROW(nbv::grid::saveMap(map, dir / "far.ot"), MapFileError);
}

}  // namespace
