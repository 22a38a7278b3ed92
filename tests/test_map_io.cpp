// Map files: .vdb round trip, OctoMap .ot/.bt export and import, and bad files.
#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"

#include "expect_file_error.hpp"
#include "octomap_compare.hpp"
#include "scenes.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

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

TEST(MapIo, ExportBeyondOctomapKeyRangeIsRefused) {
  nbv::test::TempDir dir;
  OccupancyMap map;
  map.setLogOdds({40000, 0, 0}, 1.0f);
  EXPECT_THROW(nbv::grid::saveMap(map, dir / "far.ot"), MapFileError);
}

}  // namespace
