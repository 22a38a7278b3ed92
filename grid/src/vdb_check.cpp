#include "vdb_check.hpp"

#include "nbv/errors.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

namespace nbv::grid::vdb {

namespace {

namespace fs = std::filesystem;

/// Reads fields of a file through a stream, refusing any that would run past `limit` (the
/// file's end, or the end of the grid being walked).
class Reader {
 public:
  Reader(const fs::path& path, std::uint64_t size)
      : in_(path, std::ios::binary), path_(path), size_(size), limit_(size) {
    if (!in_) throw MapFileError(path, "cannot open for reading");
  }

  [[noreturn]] void fail(const std::string& problem) const { throw MapFileError(path_, problem); }

  template <class T>
  T read(const char* what) {
    T value{};
    bytes(reinterpret_cast<char*>(&value), sizeof(T), what);
    return value;
  }
  void bytes(char* out, std::uint64_t count, const char* what) {
    take(count, what);
    in_.read(out, static_cast<std::streamsize>(count));
    if (!in_) fail(std::string("truncated in the ") + what);
  }
  void skip(std::uint64_t count, const char* what) {
    take(count, what);
    in_.seekg(static_cast<std::streamoff>(count), std::ios::cur);
  }
  /// A length-prefixed string (uint32 size, then the bytes).
  std::string string(const char* what) {
    const auto size = read<std::uint32_t>(what);
    take(size, what);  // before allocating
    std::string text(size, '\0');
    bytes(text.data(), size, what);
    return text;
  }
  std::uint64_t position() { return static_cast<std::uint64_t>(in_.tellg()); }
  std::uint64_t remaining() { return limit_ - position(); }
  std::uint64_t size() const { return size_; }
  /// Moves to `offset` and refuses reads past `limit` until the next call.
  void seek(std::uint64_t offset, std::uint64_t limit) {
    in_.seekg(static_cast<std::streamoff>(offset));
    limit_ = limit;
  }

 private:
  void take(std::uint64_t count, const char* what) {
    if (count > remaining()) {
      fail(std::string("truncated or corrupt: the ") + what + " claims " + std::to_string(count) +
           " bytes, " + std::to_string(remaining()) + " left");
    }
  }
  std::ifstream in_;
  const fs::path& path_;
  std::uint64_t size_;
  std::uint64_t limit_;
};

/// Bytes OpenVDB 10 reads for a metadata value of a registered fixed-size type, whatever
/// size the file states (TypedMetadata::readValue ignores it); 0 for a string (it reads the
/// stated size). Types outside this table are refused.
bool fixedMetadataSize(const std::string& type, std::uint32_t& bytes) {
  static const std::pair<const char*, std::uint32_t> kTypes[] = {
      {"string", 0}, {"bool", 1},   {"float", 4},  {"double", 8}, {"int32", 4},  {"int64", 8},
      {"vec2i", 8},  {"vec2s", 8},  {"vec2d", 16}, {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24},
      {"vec4i", 16}, {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}};
  for (const auto& [name, size] : kTypes) {
    if (type == name) {
      bytes = size;
      return true;
    }
  }
  return false;
}

/// A c-blosc 1 buffer of `compressed` bytes that must decompress to `expected` bytes, or up
/// to `padded` where the writer pads small buffers: its 16-byte header states both (blosc
/// trusts them when it decompresses, OpenVDB allocates what it says).
void checkBloscHeader(Reader& in, std::uint64_t compressed, std::uint64_t expected, const char* what,
                      std::uint64_t padded = 0) {
  if (compressed < 16) in.fail(std::string("corrupt compressed ") + what + " (shorter than its header)");
  std::array<std::uint8_t, 16> header{};
  in.bytes(reinterpret_cast<char*>(header.data()), header.size(), what);
  auto word = [&header](int at) {
    std::uint32_t v;
    std::memcpy(&v, header.data() + at, sizeof v);
    return v;
  };
  if (word(4) < expected || word(4) > std::max(expected, padded) || word(12) != compressed) {
    in.fail(std::string("corrupt compressed ") + what + ": it says " + std::to_string(word(4)) + " bytes in " +
            std::to_string(word(12)) + ", expected " + std::to_string(expected) + " in " + std::to_string(compressed));
  }
  in.skip(compressed - 16, what);
}

/// io::DelayedLoadMetadata::readValue's fields (a count, then two buffers, each blosc or raw).
void walkDelayedLoadMetadata(Reader& in, std::uint32_t stated) {
  if (stated == 0) return;
  const std::uint64_t start = in.position();
  const auto count = in.read<std::uint32_t>("delayed-load metadata count");
  if (count > in.remaining()) in.fail("corrupt delayed-load metadata count " + std::to_string(count));
  auto buffer = [&](std::uint64_t element_bytes, bool may_be_absent) {
    const auto compressed = in.read<std::uint32_t>("delayed-load metadata buffer");
    if (may_be_absent && compressed == std::numeric_limits<std::uint32_t>::max()) return;
    if (compressed > 0) {
      // points::bloscCompress pads buffers below 128 bytes (BLOSC_PAD_BYTES) to 128.
      checkBloscHeader(in, compressed, count * element_bytes, "delayed-load metadata buffer", 128);
    } else {
      in.skip(count * element_bytes, "delayed-load metadata buffer");
    }
  };
  buffer(1, false);  // one int8 mask per leaf
  buffer(8, true);   // one int64 compressed size per leaf, or none
  const std::uint64_t used = in.position() - start;
  if (used > stated) in.fail("corrupt delayed-load metadata (longer than it says)");
  in.skip(stated - used, "delayed-load metadata");
}

/// A MetaMap as MetaMap::readMeta reads it. Returns true if it holds
/// is_saved_as_half_float = true.
bool walkMetadata(Reader& in, const char* what) {
  const auto count = in.read<std::uint32_t>(what);
  if (count > in.remaining() / 12) in.fail(std::string("corrupt ") + what + " count " + std::to_string(count));
  bool half = false;
  for (std::uint32_t i = 0; i < count; ++i) {
    const std::string name = in.string("metadata name");
    const std::string type = in.string("metadata type");
    const auto stated = in.read<std::uint32_t>("metadata size");
    if (type == "__delayedload") {
      walkDelayedLoadMetadata(in, stated);
      continue;
    }
    std::uint32_t fixed = 0;
    if (!fixedMetadataSize(type, fixed)) in.fail("metadata '" + name + "' has an unsupported type '" + type + "'");
    if (fixed != 0 && stated != fixed) {
      in.fail("corrupt metadata '" + name + "': " + std::to_string(stated) + " bytes for a " + type);
    }
    if (name == "is_saved_as_half_float") {
      // OpenVDB reads the grid as half floats if this value is "true" as Metadata::asBool()
      // sees it, for any type (a double 10.0 too): only the bool OpenVDB writes is read here.
      if (type != "bool") in.fail("metadata 'is_saved_as_half_float' has type '" + type + "', expected 'bool'");
      half = in.read<std::uint8_t>("metadata value") != 0;
    } else {
      in.skip(stated, "metadata value");
    }
  }
  return half;
}

/// math::Transform::read: the map's type name, then its fields (linear maps only).
void walkTransform(Reader& in) {
  const std::string type = in.string("transform type");
  static const std::pair<const char*, std::uint64_t> kMaps[] = {
      {"AffineMap", 128},         {"UnitaryMap", 128},        {"ScaleMap", 120},
      {"UniformScaleMap", 120},   {"TranslationMap", 24},     {"ScaleTranslateMap", 144},
      {"UniformScaleTranslateMap", 144}};
  for (const auto& [name, bytes] : kMaps) {
    if (type == name) {
      in.skip(bytes, "transform");
      return;
    }
  }
  in.fail("unsupported transform '" + type + "' (nbv maps use a linear transform)");
}

using Mask = std::vector<std::uint64_t>;

std::uint64_t countOn(const Mask& mask) {
  std::uint64_t n = 0;
  for (std::uint64_t word : mask) n += static_cast<std::uint64_t>(std::popcount(word));
  return n;
}

/// The tree of one grid: topology first, then the leaf buffers, in OpenVDB's order.
class TreeWalk {
 public:
  TreeWalk(Reader& in, const ExpectedGrid& grid, std::uint32_t compression, const Limits& limits)
      : in_(in), grid_(grid), compression_(compression), limits_(limits) {}

  void topology() {
    if (in_.read<std::int32_t>("tree buffer count") != 1) in_.fail("grid '" + grid_.name + "': not a one-buffer tree");
    in_.skip(grid_.value_bytes, "background value");
    const auto tiles = in_.read<std::uint32_t>("root tile count");
    const auto children = in_.read<std::uint32_t>("root child count");
    if (tiles > in_.remaining() / (13 + grid_.value_bytes) || children > in_.remaining() / (12 + 2 * 4096)) {
      in_.fail("corrupt root node of grid '" + grid_.name + "': " + std::to_string(tiles) + " tiles, " +
               std::to_string(children) + " children");
    }
    constexpr std::int32_t kRootChildSpan = 1 << 12;  // voxels along an edge of a 32^3 node
    for (std::uint32_t t = 0; t < tiles; ++t) {
      readOrigin(kRootChildSpan, "root tile origin");
      in_.skip(grid_.value_bytes, "root tile value");
      const auto active = in_.read<std::uint8_t>("root tile state");
      if (active > 1) in_.fail("corrupt root tile state in grid '" + grid_.name + "'");
      if (active == 1) addTile(0, std::uint64_t{1} << 36);
    }
    std::array<std::int32_t, 3> previous{};
    for (std::uint32_t c = 0; c < children; ++c) {
      const auto origin = readOrigin(kRootChildSpan, "root child origin");
      // OpenVDB keeps the root's children in a map and reads their buffers in its (sorted)
      // order; it writes them in that order, so anything else is corrupt.
      if (c > 0 && !(previous < origin)) in_.fail("corrupt root node of grid '" + grid_.name + "': children out of order");
      previous = origin;
      internal(5);
    }
  }

  void buffers() {
    Mask mask(kLeafMaskWords);
    for (const Mask& topology_mask : leaf_masks_) {
      in_.bytes(reinterpret_cast<char*>(mask.data()), kLeafMaskWords * 8, "leaf value mask");
      if (mask != topology_mask) in_.fail("corrupt leaf in grid '" + grid_.name + "': its two value masks differ");
      compressedValues(512, mask, "leaf values");
    }
  }

 private:
  static constexpr std::size_t kLeafMaskWords = 512 / 64;

  std::array<std::int32_t, 3> readOrigin(std::int32_t span, const char* what) {
    std::array<std::int32_t, 3> origin{};
    for (auto& c : origin) {
      c = in_.read<std::int32_t>(what);
      if (c % span != 0) in_.fail(std::string("corrupt ") + what + " in grid '" + grid_.name + "' (not node-aligned)");
    }
    return origin;
  }

  /// An active tile at `level` (0 the root, 1 under a 32^3 node, 2 under a 16^3 node) of
  /// `voxels` voxels: its memory where the grid keeps tiles, else its voxels.
  void addTile(int level, std::uint64_t voxels) {
    if (grid_.tile_bytes[level] > 0) {
      addNode(grid_.tile_bytes[level]);
      return;
    }
    tile_voxels_ += voxels;
    if (tile_voxels_ > limits_.max_tile_voxels) {
      in_.fail("active tiles of grid '" + grid_.name + "' expand to more than " +
               std::to_string(limits_.max_tile_voxels) + " voxels");
    }
  }

  void addNode(std::size_t bytes) {
    tree_bytes_ += bytes;
    if (tree_bytes_ > limits_.max_tree_bytes) {
      in_.fail("the tree of grid '" + grid_.name + "' would take more than " +
               std::to_string(limits_.max_tree_bytes >> 20) + " MiB");
    }
  }

  Mask readMask(std::uint64_t bits, const char* what) {
    Mask mask(bits / 64);
    in_.bytes(reinterpret_cast<char*>(mask.data()), bits / 8, what);
    return mask;
  }

  /// An internal node of 2^(3 log2) entries (InternalNode::readTopology), then its children.
  void internal(int log2) {
    addNode(log2 == 5 ? grid_.internal5_bytes : grid_.internal4_bytes);
    const std::uint64_t entries = std::uint64_t{1} << (3 * log2);
    const Mask child_mask = readMask(entries, "internal node child mask");
    const Mask value_mask = readMask(entries, "internal node value mask");
    compressedValues(entries, value_mask, "internal node values");
    // Active tiles: a 128^3 block under a 32^3 node, an 8^3 block under a 16^3 node.
    const std::uint64_t tile_voxels = log2 == 5 ? std::uint64_t{1} << 21 : std::uint64_t{1} << 9;
    for (std::size_t w = 0; w < child_mask.size(); ++w) {
      for (auto tiles = std::popcount(value_mask[w] & ~child_mask[w]); tiles > 0; --tiles) {
        addTile(log2 == 5 ? 1 : 2, tile_voxels);
      }
    }
    for (std::size_t w = 0; w < child_mask.size(); ++w) {
      for (std::uint64_t bits = child_mask[w]; bits != 0; bits &= bits - 1) {
        if (log2 == 5) {
          internal(4);
        } else {
          addNode(grid_.leaf_bytes);
          leaf_masks_.push_back(readMask(512, "leaf value mask"));
        }
      }
    }
  }

  /// io::readCompressedValues for `entries` values selected by `value_mask`.
  void compressedValues(std::uint64_t entries, const Mask& value_mask, const char* what) {
    const auto metadata = in_.read<std::int8_t>("node compression metadata");
    if (metadata < 0 || metadata > kNoMaskAndAllVals) {
      in_.fail("corrupt node compression metadata " + std::to_string(metadata) + " in grid '" + grid_.name + "'");
    }
    if (metadata == kNoMaskAndOneInactiveVal || metadata == kMaskAndOneInactiveVal) {
      in_.skip(grid_.value_bytes, "inactive value");
    } else if (metadata == kMaskAndTwoInactiveVals) {
      in_.skip(2 * grid_.value_bytes, "inactive values");
    }
    if (metadata == kMaskAndNoInactiveVals || metadata == kMaskAndOneInactiveVal ||
        metadata == kMaskAndTwoInactiveVals) {
      in_.skip(entries / 8, "selection mask");
    }
    const bool active_only = (compression_ & kCompressActiveMask) != 0 && metadata != kNoMaskAndAllVals;
    const std::uint64_t bytes = (active_only ? countOn(value_mask) : entries) * grid_.value_bytes;
    if ((compression_ & (kCompressBlosc | kCompressZip)) == 0) {
      in_.skip(bytes, what);
      return;
    }
    // bloscFromStream / unzipFromStream: an int64 length, negative (or 0) for raw bytes.
    const auto stated = in_.read<std::int64_t>("compressed length");
    if (stated <= 0) {  // OpenVDB reads -stated bytes into a buffer of `bytes`
      const std::uint64_t raw = std::uint64_t{0} - static_cast<std::uint64_t>(stated);
      if (raw != bytes) {
        in_.fail(std::string("corrupt ") + what + " in grid '" + grid_.name + "': " + std::to_string(raw) +
                 " raw bytes stated, " + std::to_string(bytes) + " expected");
      }
      in_.skip(bytes, what);
    } else if ((compression_ & kCompressBlosc) != 0) {
      checkBloscHeader(in_, static_cast<std::uint64_t>(stated), bytes, what);
    } else {
      in_.skip(static_cast<std::uint64_t>(stated), what);
    }
  }

  Reader& in_;
  const ExpectedGrid& grid_;
  const std::uint32_t compression_;
  const Limits& limits_;
  std::vector<Mask> leaf_masks_;
  std::uint64_t tile_voxels_ = 0;
  std::uint64_t tree_bytes_ = 0;
};

/// The grid stream of Archive::readGrid: compression, metadata, transform, topology, buffers.
void walkGrid(Reader& in, const ExpectedGrid& grid, const Limits& limits) {
  const auto compression = in.read<std::uint32_t>("grid compression");
  if ((compression & ~(kCompressZip | kCompressActiveMask | kCompressBlosc)) != 0) {
    in.fail("grid '" + grid.name + "' has unknown compression flags " + std::to_string(compression));
  }
  if (walkMetadata(in, "grid metadata")) in.fail("grid '" + grid.name + "' is stored as half floats (not supported)");
  walkTransform(in);
  TreeWalk tree(in, grid, compression, limits);
  tree.topology();
  tree.buffers();
}

}  // namespace

void checkVdbFile(const fs::path& path, std::span<const ExpectedGrid> expected, const Limits& limits) {
  Reader in(path, fs::file_size(path));
  if (in.read<std::int64_t>("magic number") != kMagic) in.fail("not an OpenVDB file (wrong magic number)");
  const auto version = in.read<std::uint32_t>("file version");
  if (version < kOldestFileVersion || version > kNewestFileVersion) {
    in.fail("unsupported OpenVDB file version " + std::to_string(version));
  }
  in.read<std::uint32_t>("library major version");
  in.read<std::uint32_t>("library minor version");
  if (in.read<char>("grid offsets flag") != 1) in.fail("file has no grid offsets");
  in.skip(36, "file UUID");
  walkMetadata(in, "file metadata");
  const auto grids = in.read<std::int32_t>("grid count");
  if (grids < 0 || static_cast<std::uint64_t>(grids) > in.remaining() / 36) in.fail("corrupt grid count");
  for (std::int32_t g = 0; g < grids; ++g) {
    const std::string unique_name = in.string("grid name");
    const std::string type = in.string("grid type");
    const std::string parent = in.string("grid instance parent");
    const auto grid_pos = in.read<std::int64_t>("grid offset");
    const auto block_pos = in.read<std::int64_t>("grid block offset");
    const auto end_pos = in.read<std::int64_t>("grid end offset");
    if (grid_pos < 0 || grid_pos > block_pos || block_pos > end_pos || static_cast<std::uint64_t>(end_pos) > in.size()) {
      in.fail("truncated or corrupt: grid " + std::to_string(g) + " ends at byte " + std::to_string(end_pos) +
              " of " + std::to_string(in.size()));
    }
    if (static_cast<std::uint64_t>(grid_pos) < in.position()) {
      in.fail("corrupt: grid " + std::to_string(g) + " starts inside its descriptor");
    }
    // A unique name is the name, then "\x1e" and a number when names repeat.
    const std::string name = unique_name.substr(0, unique_name.find('\x1e'));
    const auto it = std::find_if(expected.begin(), expected.end(), [&](const ExpectedGrid& e) { return e.name == name; });
    if (it != expected.end()) {
      if (type != it->tree_type) in.fail("grid '" + name + "' has type '" + type + "', expected '" + it->tree_type + "'");
      if (!parent.empty()) in.fail("grid '" + name + "' is an instance of '" + parent + "' (not supported)");
      in.seek(static_cast<std::uint64_t>(grid_pos), static_cast<std::uint64_t>(end_pos));
      walkGrid(in, *it, limits);
    }
    in.seek(static_cast<std::uint64_t>(end_pos), in.size());  // the next descriptor follows this grid's data
  }
}

}  // namespace nbv::grid::vdb
