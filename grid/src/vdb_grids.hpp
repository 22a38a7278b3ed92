#pragma once
/// \file Private: the OpenVDB storage behind OccupancyMap, shared by the grid/ sources only.

#include "nbv/grid/occupancy_map.hpp"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <memory>

namespace nbv::grid {

/// The trees of the map in memory: 8^3 leaves (a block of the change log and the snapshot)
/// under two levels of 8^3 nodes, so a node above a leaf spans 64 voxels and one below the
/// root 512. OpenVDB's standard FloatGrid and Int32Grid put nodes of 16^3 and 32^3 children
/// there (34 KB and 270 KB each): on a map of a few hundred thousand voxels they outweighed
/// the leaves, and a map around the origin needed eight of the largest. Marks are 16-bit
/// distances (MapConfig::kMaxProximityDistance). Files keep the standard types (map_io.cpp).
using LogOddsTree = openvdb::tree::Tree4<float, 3, 3, 3>::Type;
using MarkTree = openvdb::tree::Tree4<std::uint16_t, 3, 3, 3>::Type;
using LogOddsGrid = openvdb::Grid<LogOddsTree>;
using MarkGrid = openvdb::Grid<MarkTree>;

/// Log-odds grid (active voxel = measured) and proximity grid (active voxel = marked).
/// Both have background 0 and a transform that puts voxel (i, j, k) at ((i, j, k) + 0.5) *
/// resolution in world space, matching VoxelLattice.
struct OccupancyMap::Grids {
  LogOddsGrid::Ptr log_odds;
  MarkGrid::Ptr proximity;
};

inline openvdb::Coord toCoord(const Index3& ijk) { return {ijk.x(), ijk.y(), ijk.z()}; }
inline Index3 toIndex(const openvdb::Coord& c) { return {c.x(), c.y(), c.z()}; }

/// Orders voxel indices by (i, j, k).
inline bool lessIjk(const Index3& a, const Index3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

/// The bits of an 8^3 block, bit n at OpenVDB's leaf offset n = 64 x + 8 y + z.
using BlockBits = std::array<std::uint64_t, 8>;

inline void setBit(BlockBits& bits, openvdb::Index n) { bits[n >> 6] |= std::uint64_t{1} << (n & 63); }
inline bool hasBit(const BlockBits& bits, openvdb::Index n) { return ((bits[n >> 6] >> (n & 63)) & 1u) != 0; }

inline BlockBits unionOf(const BlockBits& a, const BlockBits& b) {
  BlockBits u;
  for (std::size_t w = 0; w < u.size(); ++w) u[w] = a[w] | b[w];
  return u;
}

/// Calls visit(n) for each set bit n, in increasing order.
template <class Visit>
void forEachBit(const BlockBits& bits, Visit&& visit) {
  for (unsigned w = 0; w < 8; ++w) {
    for (std::uint64_t word = bits[w]; word != 0; word &= word - 1) {
      visit(static_cast<openvdb::Index>(64 * w + static_cast<unsigned>(std::countr_zero(word))));
    }
  }
}

/// A new grid with `source`'s transform, name and active voxels, each value converted by
/// `convert`: how a map's grids become the standard FloatGrid and Int32Grid of its files and
/// back. Copies the voxels of `source`'s leaves leaf by leaf, and each active tile as a fill of
/// its block (tiles where the target's nodes cover it whole: the trees' nodes differ above the
/// leaves).
template <class TargetGrid, class SourceGrid, class Convert>
typename TargetGrid::Ptr copyVoxels(const SourceGrid& source, Convert&& convert) {
  using TargetLeaf = typename TargetGrid::TreeType::LeafNodeType;
  static_assert(TargetLeaf::DIM == SourceGrid::TreeType::LeafNodeType::DIM);
  auto target = TargetGrid::create(typename TargetGrid::ValueType(0));
  target->setTransform(source.transform().copy());
  target->setName(source.getName());
  for (auto leaf = source.tree().cbeginLeaf(); leaf; ++leaf) {
    auto copy = std::make_unique<TargetLeaf>(leaf->origin(), typename TargetGrid::ValueType(0));
    for (auto on = leaf->cbeginValueOn(); on; ++on) copy->setValueOn(on.pos(), convert(*on));
    target->tree().addLeaf(copy.release());
  }
  auto tiles = source.tree().cbeginValueOn();
  tiles.setMaxDepth(SourceGrid::TreeType::RootNodeType::LEVEL - 1);  // the values above the leaves only
  for (; tiles; ++tiles) target->tree().fill(tiles.getBoundingBox(), convert(*tiles), /*active=*/true);
  return target;
}

/// The linear transform of an nbv grid of voxel size `resolution` [m].
openvdb::math::Transform::Ptr makeTransform(double resolution);

/// Calls openvdb::initialize() once (grid type registration for file I/O). Thread-safe.
void initializeOpenVdb();

}  // namespace nbv::grid
