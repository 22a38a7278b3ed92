#include "nbv/grid/map_io.hpp"

#include "nbv/errors.hpp"
#include "vdb_check.hpp"
#include "vdb_grids.hpp"

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>
#include <openvdb/io/File.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <mutex>
#include <sstream>
#include <unordered_set>

namespace nbv::grid {

namespace {

namespace fs = std::filesystem;

constexpr const char* kLogOddsGridName = "occupancy_log_odds";
constexpr const char* kProximityGridName = "proximity";
constexpr int kOctomapDepth = 16;            // OctoMap's 16-bit keys
constexpr int kOctomapKeyOffset = 1 << 15;   // OctoMap key of voxel index 0
/// Largest number of voxels the active tiles of a .vdb's proximity grid may expand to (marks
/// are set voxel by voxel, and a file's mark tiles are expanded): 2^22 voxels is a 1.6 m cube
/// at 1 cm. The log-odds grid keeps its tiles, and they count in memory instead.
constexpr std::uint64_t kMaxMarkTileVoxels = std::uint64_t{1} << 22;

/// What the nodes of a map's log-odds tree cost in memory [bytes]: a leaf (8^3 voxels, its
/// buffer included), the nodes above it (64^3 and 512^3 voxels), and an entry of the root's
/// table (a child or a tile of 512^3 voxels; an estimate of std::map's node).
struct TreeCosts {
  static constexpr std::size_t kLeaf = sizeof(LogOddsTree::LeafNodeType) + LogOddsTree::LeafNodeType::SIZE * sizeof(float);
  static constexpr std::size_t kLower = sizeof(LogOddsTree::RootNodeType::ChildNodeType::ChildNodeType);
  static constexpr std::size_t kUpper = sizeof(LogOddsTree::RootNodeType::ChildNodeType);
  static constexpr std::size_t kRootEntry = 64;
  static constexpr int kLeafLog2 = 3, kLowerLog2 = 6, kUpperLog2 = 9;  // the sides of their blocks
};
static_assert(LogOddsTree::LeafNodeType::DIM == 8 && LogOddsTree::RootNodeType::ChildNodeType::DIM == 512 &&
              LogOddsTree::RootNodeType::ChildNodeType::ChildNodeType::DIM == 64);

/// Throws MapFileError unless `path` is an existing, non-empty regular file.
void requireReadableFile(const fs::path& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw MapFileError(path, "no such file");
  if (fs::is_directory(status)) throw MapFileError(path, "is a directory, not a map file");
  if (!fs::is_regular_file(status)) throw MapFileError(path, "is not a regular file");
  if (fs::file_size(path, ec) == 0 || ec) throw MapFileError(path, "file is empty");
}

std::string readWholeFile(const fs::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapFileError(path, "cannot open for reading");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw MapFileError(path, "read error");
  return bytes;
}

// ------------------------------------------------------------------------------- OpenVDB --

template <class T>
T requireMeta(const openvdb::GridBase& grid, const fs::path& path, const char* name) {
  const auto meta = grid.getMetadata<openvdb::TypedMetadata<T>>(name);
  if (!meta) throw MapFileError(path, std::string("missing metadata '") + name + "'");
  return meta->value();
}

/// Memory the nodes of one grid of a .vdb file may take (checked before OpenVDB reads it):
/// a node of 32^3 entries costs over 500 KB in memory and 8 KB in a file.

static_assert(vdb::kCompressZip == openvdb::io::COMPRESS_ZIP && vdb::kCompressBlosc == openvdb::io::COMPRESS_BLOSC &&
              vdb::kCompressActiveMask == openvdb::io::COMPRESS_ACTIVE_MASK);
static_assert(vdb::kNoMaskAndOneInactiveVal == openvdb::io::NO_MASK_AND_ONE_INACTIVE_VAL &&
              vdb::kMaskAndNoInactiveVals == openvdb::io::MASK_AND_NO_INACTIVE_VALS &&
              vdb::kMaskAndOneInactiveVal == openvdb::io::MASK_AND_ONE_INACTIVE_VAL &&
              vdb::kMaskAndTwoInactiveVals == openvdb::io::MASK_AND_TWO_INACTIVE_VALS &&
              vdb::kNoMaskAndAllVals == openvdb::io::NO_MASK_AND_ALL_VALS);
static_assert(vdb::kOldestFileVersion == openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION &&
              vdb::kNewestFileVersion == openvdb::OPENVDB_FILE_VERSION && vdb::kMagic == openvdb::OPENVDB_MAGIC);

/// The grids loadVdb() reads, as checkVdbFile() walks them.
template <class GridT>
vdb::ExpectedGrid expectedGrid(const char* name) {
  using Root = typename GridT::TreeType::RootNodeType;
  using Internal5 = typename Root::ChildNodeType;
  using Internal4 = typename Internal5::ChildNodeType;
  using Leaf = typename Internal4::ChildNodeType;
  static_assert(Internal5::LOG2DIM == 5 && Internal4::LOG2DIM == 4 && Leaf::LOG2DIM == 3);
  return {name, GridT::TreeType::treeType(), sizeof(typename GridT::ValueType), sizeof(Internal5),
          sizeof(Internal4), sizeof(Leaf)};
}

/// The log-odds grid keeps a file's tiles as tiles in the map's tree: a 4096^3 root tile becomes
/// 512 root tiles (each counted as a 512^3 node, as ImportCost counts them), a 128^3 tile at
/// most a 512^3 node and its root entry, an 8^3 tile at most a 64^3 node and the nodes above it.
vdb::ExpectedGrid logOddsGridExpected() {
  vdb::ExpectedGrid grid = expectedGrid<openvdb::FloatGrid>(kLogOddsGridName);
  grid.tile_bytes[0] = 512 * (TreeCosts::kUpper + TreeCosts::kRootEntry);  // as ImportCost counts a root tile
  grid.tile_bytes[1] = TreeCosts::kUpper + TreeCosts::kRootEntry;
  grid.tile_bytes[2] = TreeCosts::kLower + TreeCosts::kUpper + TreeCosts::kRootEntry;
  return grid;
}

void saveVdb(const OccupancyMap& map, const fs::path& path) {
  initializeOpenVdb();
  const OccupancyMap::Config& c = map.config();
  openvdb::GridPtrVec grids;
  // Files hold OpenVDB's standard grid types, whatever trees the map keeps in memory.
  auto log_odds = copyVoxels<openvdb::FloatGrid>(*map.grids().log_odds, [](float v) { return v; });
  log_odds->insertMeta("nbv_sensor_model",
                       openvdb::StringMetadata("octomap_log_odds (occupancy log-odds per voxel, "
                                               "OctoMap insertPointCloud semantics)"));
  log_odds->insertMeta("nbv_format_version", openvdb::Int32Metadata(1));
  for (const MapConfigField& f : mapConfigFields()) {
    log_odds->insertMeta(std::string("nbv_") + f.name, openvdb::DoubleMetadata(c.*f.member));
  }
  grids.push_back(log_odds);
  grids.push_back(copyVoxels<openvdb::Int32Grid>(*map.grids().proximity,
                                                 [](MarkTree::ValueType d) { return std::int32_t{d}; }));
  try {
    openvdb::io::File file(path.string());
    file.write(grids);
    file.close();
  } catch (const std::exception& e) {
    throw MapFileError(path, std::string("cannot write OpenVDB file: ") + e.what());
  }
}

OccupancyMap loadVdb(const fs::path& path, std::size_t max_bytes) {
  requireReadableFile(path);
  initializeOpenVdb();
  const vdb::ExpectedGrid grids[] = {logOddsGridExpected(), expectedGrid<openvdb::Int32Grid>(kProximityGridName)};
  vdb::checkVdbFile(path, grids, {kMaxMarkTileVoxels, max_bytes});
  openvdb::FloatGrid::Ptr log_odds;
  openvdb::Int32Grid::Ptr proximity;
  try {
    openvdb::io::File file(path.string());
    file.open(/*delayLoad=*/false);
    if (!file.hasGrid(kLogOddsGridName)) {
      throw MapFileError(path, std::string("no grid named '") + kLogOddsGridName +
                                   "' (not an nbv map)");
    }
    log_odds = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(kLogOddsGridName));
    if (file.hasGrid(kProximityGridName)) {
      proximity = openvdb::gridPtrCast<openvdb::Int32Grid>(file.readGrid(kProximityGridName));
      if (!proximity) throw MapFileError(path, "grid 'proximity' is not an Int32 grid");
    }
    file.close();
  } catch (const MapFileError&) {
    throw;
  } catch (const std::exception& e) {
    throw MapFileError(path, std::string("not a readable OpenVDB file: ") + e.what());
  }
  if (!log_odds) throw MapFileError(path, "grid 'occupancy_log_odds' is not a float grid");

  OccupancyMap::Config config;
  const auto fields = mapConfigFields();
  for (std::size_t i = 0; i < fields.size(); ++i) {
    const std::string key = std::string("nbv_") + fields[i].name;
    // Maps written before a later field existed lack it: it reads as its default.
    if (i < kFirstMapConfigFields) {
      config.*fields[i].member = requireMeta<double>(*log_odds, path, key.c_str());
    } else if (const auto value = log_odds->getMetadata<openvdb::DoubleMetadata>(key)) {
      config.*fields[i].member = value->value();
    }
  }
  try {
    config.validate();
  } catch (const InvalidArgument& e) {
    throw MapFileError(path, e.what());
  }
  const openvdb::math::Transform expected = *makeTransform(config.resolution);
  if (log_odds->transform() != expected || (proximity && proximity->transform() != expected)) {
    throw MapFileError(path, "grid transform does not match the stored resolution");
  }
  if (log_odds->background() != 0.0f || (proximity && proximity->background() != 0)) {
    throw MapFileError(path, "grid background is not 0");
  }
  // Tiles stay tiles (integration turns the one a scan touches into voxels); marks are set
  // voxel by voxel: a foreign writer's mark tiles are expanded.
  for (auto it = log_odds->cbeginValueOn(); it; ++it) {
    if (!std::isfinite(*it)) {
      const openvdb::Coord c = it.getCoord();
      throw MapFileError(path, "non-finite log-odds at voxel (" + std::to_string(c.x()) + ", " +
                                   std::to_string(c.y()) + ", " + std::to_string(c.z()) + ")");
    }
  }
  if (proximity) {
    proximity->tree().voxelizeActiveTiles();
    for (auto it = proximity->cbeginValueOn(); it; ++it) {
      const openvdb::Coord c = it.getCoord();
      const auto at_voxel = [&c] {  // spelt out only for an error
        return " at voxel (" + std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " + std::to_string(c.z()) + ")";
      };
      if (*it < 1 || *it > OccupancyMap::Config::kMaxProximityDistance) {
        throw MapFileError(path, "proximity mark " + std::to_string(*it) + at_voxel() + " is outside [1, " +
                                     std::to_string(OccupancyMap::Config::kMaxProximityDistance) + "]");
      }
      if (log_odds->tree().isValueOn(c)) throw MapFileError(path, "proximity mark on a measured voxel" + at_voxel());
    }
  }

  OccupancyMap map(config);
  // (The copies keep the grids' names and leave the file's metadata behind.)
  auto& held = map.grids();
  held.log_odds = copyVoxels<LogOddsGrid>(*log_odds, [](float v) { return v; });
  if (proximity) {
    held.proximity = copyVoxels<MarkGrid>(
        *proximity, [](std::int32_t d) { return static_cast<MarkTree::ValueType>(d); });
  }
  return map;
}

// -------------------------------------------------------------------------------- OctoMap --

/// An occupancy octree type of liboctomap nbv reads: its id in a file's header, what a node of
/// its `.ot` data holds after the log-odds, and what of that an imported map drops.
struct OctomapTreeType {
  const char* id;
  std::size_t extra_bytes;  ///< per node of `.ot` data, after the float log-odds
  const char* dropped;      ///< empty: nothing
};
/// OcTreeStamped's nodes keep a time stamp in memory, but its files hold none (liboctomap 1.9
/// writes only the log-odds); ColorOcTree's hold three colour bytes. Binary (.bt) data is the
/// same for all three: two bits per child. ("1": the id of old binary files.)
constexpr OctomapTreeType kOctomapTreeTypes[] = {
    {"OcTree", 0, ""}, {"1", 0, ""}, {"ColorOcTree", 3, "colours"}, {"OcTreeStamped", 0, ""}};

/// Header fields of an OctoMap file, parsed as AbstractOcTree::readHeader does.
struct OctomapHeader {
  std::string id;
  const OctomapTreeType* type = nullptr;
  std::uint64_t size = 0;
  double resolution = 0.0;
  std::size_t data_offset = 0;
};

OctomapHeader parseOctomapHeader(const std::string& bytes, const fs::path& path,
                                 const std::string& first_line) {
  OctomapHeader header;
  std::size_t pos = bytes.find('\n');
  if (pos == std::string::npos || bytes.compare(0, first_line.size(), first_line) != 0) {
    throw MapFileError(path, "first line is not '" + first_line + "'");
  }
  ++pos;
  bool have_size = false;
  while (pos < bytes.size()) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) break;
    std::istringstream line(bytes.substr(pos, eol - pos));
    pos = eol + 1;
    std::string token;
    if (!(line >> token) || token[0] == '#') continue;
    if (token == "data") {
      header.data_offset = pos;
      for (const OctomapTreeType& type : kOctomapTreeTypes) {
        if (header.id == type.id) header.type = &type;
      }
      if (header.type == nullptr) {
        throw MapFileError(path, "tree type '" + header.id + "' is not an occupancy tree nbv reads (OcTree, "
                                 "ColorOcTree, OcTreeStamped)");
      }
      if (!std::isfinite(header.resolution) || header.resolution <= 0.0) {
        throw MapFileError(path, "resolution is missing or not > 0");
      }
      if (!have_size) throw MapFileError(path, "header has no 'size'");
      return header;
    }
    if (token == "id") {
      line >> header.id;
    } else if (token == "res") {
      if (!(line >> header.resolution)) throw MapFileError(path, "unreadable 'res' in header");
    } else if (token == "size") {
      if (!(line >> header.size)) throw MapFileError(path, "unreadable 'size' in header");
      have_size = true;
    }
  }
  throw MapFileError(path, "header has no 'data' line (truncated or not an OctoMap file)");
}

/// Walks the node structure of an OctoMap body without building it: bounded depth, bounded
/// bytes, so that garbage can neither recurse forever nor read past the end.
class OctomapBodyCheck {
 public:
  OctomapBodyCheck(const std::string& bytes, const OctomapHeader& header, bool binary, const fs::path& path)
      : bytes_(bytes), pos_(header.data_offset), binary_(binary), extra_bytes_(header.type->extra_bytes),
        path_(path) {}

  void run(std::uint64_t expected_nodes) {
    ++nodes_;  // the root
    if (binary_) {
      binaryNode(0);
    } else {
      fullNode(0);
    }
    if (nodes_ != expected_nodes) {
      throw MapFileError(path_, "header says " + std::to_string(expected_nodes) +
                                    " nodes, data holds " + std::to_string(nodes_));
    }
  }

 private:
  const unsigned char* take(std::size_t count) {
    if (bytes_.size() - pos_ < count) throw MapFileError(path_, "truncated tree data");
    const auto* p = reinterpret_cast<const unsigned char*>(bytes_.data()) + pos_;
    pos_ += count;
    return p;
  }
  void fullNode(int depth) {  // .ot: float log-odds (and the tree type's extra bytes), then one byte of child flags
    float value;
    std::memcpy(&value, take(sizeof(float)), sizeof(float));
    take(extra_bytes_);
    const unsigned children = *take(1);
    if (children == 0) {
      if (!std::isfinite(value)) throw MapFileError(path_, "non-finite log-odds in tree data");
      return;
    }
    if (depth == kOctomapDepth) throw MapFileError(path_, "tree deeper than 16 levels");
    for (int i = 0; i < 8; ++i) {
      if ((children >> i) & 1u) {
        ++nodes_;
        fullNode(depth + 1);
      }
    }
  }
  void binaryNode(int depth) {  // .bt: two bytes, 2 bits per child
    if (depth == kOctomapDepth) throw MapFileError(path_, "tree deeper than 16 levels");
    const unsigned char* flags = take(2);
    int inner_count = 0;
    for (int i = 0; i < 8; ++i) {
      const unsigned bits = (flags[i / 4] >> (2 * (i % 4))) & 3u;
      if (bits == 0) continue;
      ++nodes_;
      if (bits == 3) ++inner_count;
    }
    for (int k = 0; k < inner_count; ++k) binaryNode(depth + 1);
  }

  const std::string& bytes_;
  std::size_t pos_;
  bool binary_;
  std::size_t extra_bytes_;
  const fs::path& path_;
  std::uint64_t nodes_ = 0;
};

/// Captures what liboctomap writes to std::cerr (Debian's build prints progress lines) for the
/// guard's lifetime, so library users see no chatter; the text can go into an error message.
/// One capture at a time in the process (std::cerr is global): concurrent OctoMap reads and
/// writes take turns; other threads' std::cerr output meanwhile lands in the capture.
class CerrCapture {
 public:
  CerrCapture() : turn_(mutex()), previous_(std::cerr.rdbuf(captured_.rdbuf())) {}
  ~CerrCapture() { std::cerr.rdbuf(previous_); }
  CerrCapture(const CerrCapture&) = delete;
  CerrCapture& operator=(const CerrCapture&) = delete;
  std::string text() const {
    std::string t = captured_.str();
    while (!t.empty() && (t.back() == '\n' || t.back() == ' ')) t.pop_back();
    return t.empty() ? "" : " (" + t + ")";
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> turn_;
  std::ostringstream captured_;
  std::streambuf* previous_;
};

void configureTree(octomap::OcTree& tree, const OccupancyMap::Config& c) {
  tree.setProbHit(c.p_hit);
  tree.setProbMiss(c.p_miss);
  tree.setClampingThresMin(c.clamp_min);
  tree.setClampingThresMax(c.clamp_max);
  tree.setOccupancyThres(0.5);
}

/// A .bt file byte for byte as liboctomap's OcTree::writeBinary() writes it (maximum-likelihood
/// values, pruned), without the " done." that Debian's liboctomap prints on stderr after it.
bool writeOctomapBinary(octomap::OcTree& tree, const fs::path& path) {
  tree.toMaxLikelihood();
  tree.prune();
  std::ofstream out(path, std::ios::binary);
  out << "# Octomap OcTree binary file\n# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
      << "id " << tree.getTreeType() << "\nsize " << tree.size() << "\nres " << tree.getResolution() << "\ndata\n";
  tree.writeBinaryData(out);
  return static_cast<bool>(out.flush());
}

/// The OctoMap key of voxel index `ijk`. \throws MapFileError outside OctoMap's 16-bit keys.
octomap::OcTreeKey octomapKey(const openvdb::Coord& ijk, const fs::path& path) {
  for (int a = 0; a < 3; ++a) {
    if (ijk[a] < -kOctomapKeyOffset || ijk[a] >= kOctomapKeyOffset) {
      throw MapFileError(path, "map extends beyond OctoMap's 16-bit key range");
    }
  }
  return octomap::OcTreeKey(static_cast<octomap::key_type>(ijk.x() + kOctomapKeyOffset),
                            static_cast<octomap::key_type>(ijk.y() + kOctomapKeyOffset),
                            static_cast<octomap::key_type>(ijk.z() + kOctomapKeyOffset));
}

/// Makes the node at `depth` whose cube starts at `key` a leaf of value `value`: OctoMap's
/// pruned node for a cube of identical voxels (an OpenVDB tile). liboctomap's own way: the
/// voxel at `key`, then from its parent up to that node each one's other children set to the
/// value and the node pruned into one leaf.
void setPrunedNode(octomap::OcTree& tree, const octomap::OcTreeKey& key, int depth, float value) {
  tree.setNodeValue(key, value, /*lazy_eval=*/true);
  std::array<octomap::OcTreeNode*, kOctomapDepth> path{};  // path[d]: the node at depth d above the voxel
  path[0] = tree.getRoot();
  for (int d = 0; d + 1 < kOctomapDepth; ++d) {
    path[d + 1] = tree.getNodeChild(path[d], octomap::computeChildIdx(key, kOctomapDepth - 1 - d));
  }
  for (int d = kOctomapDepth - 1; d >= depth; --d) {
    for (unsigned child = 0; child < 8; ++child) {
      if (!tree.nodeChildExists(path[d], child)) tree.createNodeChild(path[d], child)->setLogOdds(value);
    }
    tree.pruneNode(path[d]);
  }
}

void saveOctomap(const OccupancyMap& map, const fs::path& path, MapFormat format) {
  octomap::OcTree tree(map.config().resolution);
  configureTree(tree, map.config());
  const LogOddsTree& voxels = map.grids().log_odds->tree();
  // Tiles as pruned nodes (a tile's side is a power of two at least 8, aligned to it, as an
  // OctoMap node's cube is: voxel index 0 is key 2^15), then the leaves' voxels.
  auto tiles = voxels.cbeginValueOn();
  tiles.setMaxDepth(LogOddsTree::RootNodeType::LEVEL - 1);  // the root's and the inner nodes' values only
  for (; tiles; ++tiles) {
    const openvdb::CoordBBox box = tiles.getBoundingBox();
    octomapKey(box.max(), path);  // (its last voxel within OctoMap's keys, or refused)
    const int side_log2 = std::countr_zero(static_cast<unsigned>(box.dim().x()));
    setPrunedNode(tree, octomapKey(box.min(), path), kOctomapDepth - side_log2, *tiles);
  }
  for (auto leaf = voxels.cbeginLeaf(); leaf; ++leaf) {
    for (auto v = leaf->cbeginValueOn(); v; ++v) tree.setNodeValue(octomapKey(v.getCoord(), path), *v, /*lazy_eval=*/true);
  }
  tree.updateInnerOccupancy();
  tree.prune();  // lossless: merges only identical siblings
  CerrCapture octomap_messages;
  const bool written = format == MapFormat::OctomapOt ? tree.write(path.string()) : writeOctomapBinary(tree, path);
  if (!written) throw MapFileError(path, "cannot write OctoMap file" + octomap_messages.text());
}

/// The leaves of an occupancy tree liboctomap read: visit(key of the cube's first voxel, the
/// cube's side log2, log-odds) for each, in the tree's order.
template <class Visit>
void forEachOctomapLeaf(octomap::AbstractOcTree& tree, const fs::path& path, Visit&& visit) {
  const auto leaves = [&](auto& typed) {
    for (auto it = typed.begin_leafs(), end = typed.end_leafs(); it != end; ++it) {
      visit(it.getIndexKey(), kOctomapDepth - static_cast<int>(it.getDepth()), it->getLogOdds());
    }
  };
  if (auto* t = dynamic_cast<octomap::OcTree*>(&tree)) return leaves(*t);
  if (auto* t = dynamic_cast<octomap::ColorOcTree*>(&tree)) return leaves(*t);
  if (auto* t = dynamic_cast<octomap::OcTreeStamped*>(&tree)) return leaves(*t);
  throw MapFileError(path, "liboctomap read a tree of type '" + tree.getTreeType() + "', not an occupancy tree");
}

/// The memory [bytes] the map's log-odds tree takes for OctoMap leaves (a cube of side 2^log2
/// from index `ijk` each), reckoned before any is set: the leaves, the nodes above them and the
/// root's entries their cubes need, each counted once, and the root's tiles (cubes of 512^3
/// voxels or more).
class ImportCost {
 public:
  void add(const Index3& ijk, int log2) {
    if (log2 >= TreeCosts::kUpperLog2) {
      root_tiles_ += std::uint64_t{1} << (3 * (log2 - TreeCosts::kUpperLog2));  // (log2 <= 16: at most 2^21)
      return;
    }
    if (log2 < TreeCosts::kLeafLog2) leaves_.insert(block(ijk, TreeCosts::kLeafLog2));
    if (log2 < TreeCosts::kLowerLog2) lower_.insert(block(ijk, TreeCosts::kLowerLog2));
    upper_.insert(block(ijk, TreeCosts::kUpperLog2));
  }
  /// A tile of the root is counted as the 512^3 node a scan through it would make of it: a
  /// root of millions of tiles (a few bytes of a pruned tree) costs little memory but slows
  /// every walk over the map's values.
  std::uint64_t bytes() const {
    return leaves_.size() * TreeCosts::kLeaf + lower_.size() * TreeCosts::kLower +
           (upper_.size() + root_tiles_) * (TreeCosts::kUpper + TreeCosts::kRootEntry);
  }

 private:
  /// The block of side 2^log2 holding voxel `ijk`, as one number (indices fit 21 bits).
  static std::uint64_t block(const Index3& ijk, int log2) {
    std::uint64_t key = 0;
    for (int a = 0; a < 3; ++a) key = key << 21 | (static_cast<std::uint64_t>(ijk[a] >> log2) & 0x1FFFFF);
    return key;
  }
  std::unordered_set<std::uint64_t> leaves_, lower_, upper_;
  std::uint64_t root_tiles_ = 0;
};

/// "12.3 MB".
std::string megabytes(std::uint64_t bytes) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(1) << static_cast<double>(bytes) * 1e-6 << " MB";
  return text.str();
}

/// liboctomap's tree of a checked file: .bt through OcTree::readBinary (binary data is the same
/// for every occupancy tree type), .ot through AbstractOcTree::read (which builds the type the
/// header names).
std::unique_ptr<octomap::AbstractOcTree> readOctomapTree(const std::string& bytes, const OctomapHeader& header,
                                                         bool binary, const OccupancyMap::Config& config,
                                                         const fs::path& path) {
  std::istringstream in(bytes);
  CerrCapture octomap_messages;
  if (binary) {
    auto tree = std::make_unique<octomap::OcTree>(header.resolution);
    configureTree(*tree, config);
    if (!tree->readBinary(in)) throw MapFileError(path, "liboctomap could not read the file" + octomap_messages.text());
    return tree;
  }
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(in));
  if (tree == nullptr) throw MapFileError(path, "liboctomap could not read the tree" + octomap_messages.text());
  return tree;
}

OccupancyMap loadOctomap(const fs::path& path, MapFormat format, const MapLoadOptions& options,
                         MapLoadReport* report) {
  const bool binary = format == MapFormat::OctomapBt;
  const std::string bytes = readWholeFile(path);
  const OctomapHeader header = parseOctomapHeader(
      bytes, path, binary ? "# Octomap OcTree binary file" : "# Octomap OcTree file");
  OccupancyMap::Config config = options.config;
  config.resolution = header.resolution;
  try {
    config.validate();
  } catch (const InvalidArgument& e) {
    throw MapFileError(path, e.what());
  }
  OccupancyMap map(config);
  if (report != nullptr) *report = {header.type->id == std::string("1") ? "OcTree" : header.type->id, ""};
  if (header.size == 0) return map;  // OctoMap writes no node data for an empty tree
  OctomapBodyCheck(bytes, header, binary, path).run(header.size);

  // The structure is sound: let liboctomap read it, then reckon the map's memory on the tree it
  // built (its header parser is not ours, so a count on nbv's own walk of the bytes could be
  // fooled), before any voxel is set.
  const std::unique_ptr<octomap::AbstractOcTree> tree = readOctomapTree(bytes, header, binary, config, path);
  const auto index = [](const octomap::OcTreeKey& key) {
    return Index3(key[0] - kOctomapKeyOffset, key[1] - kOctomapKeyOffset, key[2] - kOctomapKeyOffset);
  };
  ImportCost cost;
  std::size_t leaves = 0;
  forEachOctomapLeaf(*tree, path, [&](const octomap::OcTreeKey& key, int log2, float) {
    cost.add(index(key), log2);
    ++leaves;
  });
  if (cost.bytes() > options.max_bytes) {
    throw MapFileError(path, "the map would take about " + megabytes(cost.bytes()) + ", more than the cap of " +
                                 megabytes(options.max_bytes) + " (MapLoadOptions::max_bytes)");
  }
  // A pruned node is one tile (a fill, which makes tiles of the blocks it covers whole and
  // voxels of the rest); a voxel is set through an accessor, cleared after each fill (a fill
  // may replace the nodes it caches).
  const float lowest = OccupancyMap::logOddsOf(config.clamp_min), highest = OccupancyMap::logOddsOf(config.clamp_max);
  LogOddsTree& voxels = map.grids().log_odds->tree();
  openvdb::tree::ValueAccessor<LogOddsTree> accessor(voxels);
  forEachOctomapLeaf(*tree, path, [&](const octomap::OcTreeKey& key, int log2, float log_odds) {
    const float value = std::clamp(log_odds, lowest, highest);
    const openvdb::Coord first = toCoord(index(key));
    if (log2 == 0) {
      accessor.setValueOn(first, value);
      return;
    }
    voxels.fill(openvdb::CoordBBox::createCube(first, 1 << log2), value, /*active=*/true);
    accessor.clear();
  });
  if (report != nullptr && header.type->dropped[0] != '\0' && !binary) {
    report->dropped = std::string("the ") + header.type->dropped + " of " + std::to_string(leaves) + " nodes";
  }
  return map;
}

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return ext;
}

}  // namespace

MapFormat mapFormatFromPath(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".vdb") return MapFormat::Vdb;
  if (ext == ".ot") return MapFormat::OctomapOt;
  if (ext == ".bt") return MapFormat::OctomapBt;
  if (ext.empty()) throw MapFileError(path, "no extension to tell the map format by (name it .vdb, .ot or .bt)");
  throw MapFileError(path, "unknown map format '" + ext + "' (expected .vdb, .ot or .bt)");
}

void saveMap(const OccupancyMap& map, const fs::path& path, MapFormat format) {
  if (format == MapFormat::Vdb) {
    saveVdb(map, path);
  } else {
    saveOctomap(map, path, format);
  }
}

void saveMap(const OccupancyMap& map, const fs::path& path) {
  saveMap(map, path, mapFormatFromPath(path));
}

namespace {

OccupancyMap loadMapAs(const fs::path& path, MapFormat format, const MapLoadOptions& options, MapLoadReport* report) {
  if (format != MapFormat::Vdb) return loadOctomap(path, format, options, report);
  if (report != nullptr) *report = {};
  return loadVdb(path, options.max_bytes);
}

}  // namespace

OccupancyMap loadMap(const fs::path& path, const MapLoadOptions& options, MapLoadReport* report) {
  return loadMapAs(path, mapFormatFromPath(path), options, report);
}

OccupancyMap loadMap(const fs::path& path, MapFormat format, const OccupancyMap::Config& base_config) {
  MapLoadOptions options;
  options.config = base_config;
  return loadMapAs(path, format, options, nullptr);
}

OccupancyMap loadMap(const fs::path& path) { return loadMap(path, mapFormatFromPath(path)); }

}  // namespace nbv::grid
