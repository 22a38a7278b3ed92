#pragma once
// Private to the tests: the LaneDda templates of lanes_check.hpp, for one lane width S. Included
// after S's header, inside the target options of the source that instantiates them.

#include "dda_lanes.hpp"
#include "lanes_check.hpp"

namespace nbv::test {

/// The rays origins[i] -> ends[i] (equal sizes, a multiple of S::kLanes) through LaneDda<S>.
template <class S>
std::vector<LaneSetupRow> setupInLanes(const std::vector<Eigen::Vector3f>& origins,
                                       const std::vector<Eigen::Vector3f>& ends, const kernels::VoxelLattice& lattice) {
  constexpr int kLanes = S::kLanes;
  using Dda = kernels::detail::LaneDda<S>;
  std::vector<LaneSetupRow> rows(ends.size());
  for (std::size_t first = 0; first < ends.size(); first += kLanes) {
    alignas(64) float points[2][3][kLanes];
    for (int j = 0; j < kLanes; ++j) {
      for (int a = 0; a < 3; ++a) {
        points[0][a][j] = origins[first + j][a];
        points[1][a][j] = ends[first + j][a];
      }
    }
    const typename S::F origin[3] = {S::loadF(points[0][0]), S::loadF(points[0][1]), S::loadF(points[0][2])};
    const typename S::F end[3] = {S::loadF(points[1][0]), S::loadF(points[1][1]), S::loadF(points[1][2])};
    typename Dda::Setup s;
    const unsigned same = S::bits(Dda::setup(origin, end, lattice, s));
    alignas(64) double column[kLanes];
    const auto each = [&](typename S::D v, auto&& put) {
      S::store(column, v);
      for (int j = 0; j < kLanes; ++j) put(rows[first + j], column[j]);
    };
    for (int a = 0; a < 3; ++a) {
      each(s.key_origin[a], [a](LaneSetupRow& r, double v) { r.key_origin[a] = v; });
      each(s.key_end[a], [a](LaneSetupRow& r, double v) { r.key_end[a] = v; });
      each(s.step[a], [a](LaneSetupRow& r, double v) { r.step[a] = v; });
      each(s.t_max[a], [a](LaneSetupRow& r, double v) { r.t_max[a] = v; });
      each(s.t_delta[a], [a](LaneSetupRow& r, double v) { r.t_delta[a] = v; });
    }
    each(s.length, [](LaneSetupRow& r, double v) { r.length = v; });
    for (int j = 0; j < kLanes; ++j) rows[first + j].same_voxel = ((same >> j) & 1u) != 0;
  }
  return rows;
}

/// The voxels of each ray as LaneDda::step() walks it, its voxel carried as one offset
/// (x + 4096) + (y + 4096) 2^13 + (z + 4096) 2^26 (keys within +-4096), as the packet walks
/// carry a box offset.
template <class S>
LaneWalks walkInLanes(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& ends,
                      const kernels::VoxelLattice& lattice, int max_steps) {
  constexpr int kLanes = S::kLanes;
  using Dda = kernels::detail::LaneDda<S>;
  using D = typename S::D;
  const std::vector<LaneSetupRow> rows = setupInLanes<S>(origins, ends, lattice);
  const double scale[3] = {1.0, 8192.0, 8192.0 * 8192.0};
  const auto offsetOf = [&scale](const double key[3]) {
    return (key[0] + 4096.0) * scale[0] + (key[1] + 4096.0) * scale[1] + (key[2] + 4096.0) * scale[2];
  };
  LaneWalks walks(ends.size());
  for (std::size_t first = 0; first < ends.size(); first += kLanes) {
    alignas(64) double columns[12][kLanes];  // t_max (3), t_delta (3), offset step (3), offset, end, length
    unsigned ended = 0;
    for (int j = 0; j < kLanes; ++j) {
      const LaneSetupRow& r = rows[first + j];
      for (int a = 0; a < 3; ++a) {
        columns[a][j] = r.t_max[a];
        columns[3 + a][j] = r.t_delta[a];
        columns[6 + a][j] = r.step[a] * scale[a];
      }
      columns[9][j] = offsetOf(r.key_origin);
      columns[10][j] = offsetOf(r.key_end);
      columns[11][j] = r.length;
      if (r.same_voxel) ended |= 1u << j;
      else walks[first + j].emplace_back(static_cast<int>(r.key_origin[0]), static_cast<int>(r.key_origin[1]),
                                         static_cast<int>(r.key_origin[2]));
    }
    D tx = S::load(columns[0]), ty = S::load(columns[1]), tz = S::load(columns[2]), offset = S::load(columns[9]);
    const D dx = S::load(columns[3]), dy = S::load(columns[4]), dz = S::load(columns[5]);
    const D ox = S::load(columns[6]), oy = S::load(columns[7]), oz = S::load(columns[8]);
    const D end = S::load(columns[10]), length = S::load(columns[11]);
    for (int k = 0; k < max_steps && ended != (1u << kLanes) - 1u; ++k) {
      Dda::step(tx, ty, tz, dx, dy, dz, offset, ox, oy, oz);
      ended |= S::bits(S::either(S::eq(offset, end), Dda::pastLength(tx, ty, tz, length)));
      alignas(64) double at[kLanes];
      S::store(at, offset);
      for (int j = 0; j < kLanes; ++j) {
        if ((ended >> j) & 1u) continue;
        const auto code = static_cast<long long>(at[j]);
        walks[first + j].emplace_back(static_cast<int>(code % 8192) - 4096, static_cast<int>(code / 8192 % 8192) - 4096,
                                      static_cast<int>(code / (8192 * 8192)) - 4096);
      }
    }
  }
  return walks;
}

}  // namespace nbv::test
