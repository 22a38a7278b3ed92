#pragma once
/// \file Private: the walk over an OpenVDB file that loadVdb() runs before OpenVDB reads it.
///
/// OpenVDB 10's reader trusts every length and count a file states: a corrupt file makes it
/// allocate what a buffer length says (gigabytes), read past a buffer (a negative length
/// larger than the buffer is copied into it), loop over billions of claimed nodes, or expand
/// an active tile into billions of voxels. checkVdbFile() reads every field OpenVDB would
/// read for the grids nbv loads, in OpenVDB's order, and refuses the file unless each length
/// and count fits the bytes that remain and the tree stays within the limits. It includes no
/// OpenVDB header; map_io.cpp checks the format constants below against OpenVDB's own.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace nbv::grid::vdb {

// OpenVDB 10's io/Compression.h: grid compression flags.
inline constexpr std::uint32_t kCompressZip = 0x1;
inline constexpr std::uint32_t kCompressActiveMask = 0x2;
inline constexpr std::uint32_t kCompressBlosc = 0x4;
// The per-node metadata byte of readCompressedValues().
inline constexpr std::int8_t kNoMaskAndOneInactiveVal = 2;
inline constexpr std::int8_t kMaskAndNoInactiveVals = 3;
inline constexpr std::int8_t kMaskAndOneInactiveVal = 4;
inline constexpr std::int8_t kMaskAndTwoInactiveVals = 5;
inline constexpr std::int8_t kNoMaskAndAllVals = 6;
/// The oldest and newest file versions walked (OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION
/// and OPENVDB_FILE_VERSION of OpenVDB 10).
inline constexpr std::uint32_t kOldestFileVersion = 222;
inline constexpr std::uint32_t kNewestFileVersion = 224;
inline constexpr std::int64_t kMagic = 0x56444220;  ///< OPENVDB_MAGIC: " BDV"

/// A grid loadVdb() reads: its name, the tree type OpenVDB writes for it, and what one node
/// of each level costs in memory.
struct ExpectedGrid {
  std::string name;
  std::string tree_type;           ///< e.g. "Tree_float_5_4_3" (5-4-3 trees only)
  std::size_t value_bytes;         ///< sizeof(ValueType)
  std::size_t internal5_bytes;     ///< sizeof of the 32^3 internal node
  std::size_t internal4_bytes;     ///< sizeof of the 16^3 internal node
  std::size_t leaf_bytes;          ///< sizeof of the 8^3 leaf
  /// What an active tile costs where the grid keeps its tiles as tiles: a tile of the root (a
  /// 4096^3 block), one under a 32^3 node (128^3) and one under a 16^3 node (8^3), counted
  /// against Limits::max_tree_bytes; all 0 where the tiles are expanded to voxels, which count
  /// against Limits::max_tile_voxels.
  std::size_t tile_bytes[3] = {0, 0, 0};
};

struct Limits {
  std::uint64_t max_tile_voxels;   ///< voxels that active tiles of a grid that expands them may expand to
  std::uint64_t max_tree_bytes;    ///< memory the nodes (and the kept tiles) of one grid may take
};

/// Throws MapFileError naming `path` and the first field that is out of range. Grids not in
/// `expected` are only skipped (OpenVDB never reads them); a grid named as one in `expected`
/// must have its tree type, and must not be an instance or stored as half floats.
void checkVdbFile(const std::filesystem::path& path, std::span<const ExpectedGrid> expected,
                  const Limits& limits);

}  // namespace nbv::grid::vdb
