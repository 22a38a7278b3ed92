// The IG ray kernel alone, fast: a small snapshot box of five kinds of voxel (unmeasured,
// free, occupied, marked, measured unknown) with exact run distances in every octant: each
// voxel drawn, or boxes of one kind laid over one another (runs of every kind, which the walks
// cross in closed form); or a larger empty box with up to four voxels of the other kinds (runs
// up to 31 voxels); one camera origin and
// rays to end points on or near voxel borders (where OctoMap's walk stops short of its end
// key or steps past its slab). Invariants: every instruction set gives the same bits, and
// each ray's sums equal a voxel-by-voxel sum over OctoMap's keys (the kernel's closed forms
// and skips to within rounding, counts and classes exactly).
#include "fuzz_input_file.hpp"
#include "../ray_oracle.hpp"

#include "nbv/kernels/ig_rays.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <vector>

namespace {

using nbv::kernels::RayCounts;
using nbv::kernels::RaySums;
using nbv::kernels::SnapshotEntry;
using nbv::kernels::VoxelTerms;

/// Reads bytes in order, then zeros.
struct Bytes {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  std::uint8_t next() { return at < size ? data[at++] : 0; }
};

/// A point on the lattice (a multiple of `reach` voxels, in [-16, 16) times `reach` voxels) plus,
/// for odd bytes, a fraction of a voxel.
Eigen::Vector3f point(Bytes& in, float resolution, int reach) {
  Eigen::Vector3f p;
  for (int a = 0; a < 3; ++a) {
    const std::uint8_t b = in.next();
    p[a] = static_cast<float>((static_cast<int>(b % 32) - 16) * reach) * resolution;
    if ((b & 1) != 0) p[a] += static_cast<float>(in.next()) / 256.0f * resolution;
  }
  return p;
}

bool sameSums(const RaySums& a, const RaySums& b) {
  return a.entropy == b.entropy && a.oa == b.oa && a.uv == b.uv && a.rse == b.rse && a.pc == b.pc &&
         a.voxels == b.voxels && a.end_occupied == b.end_occupied && a.rear_side == b.rear_side && a.area == b.area;
}

bool near(double got, double expected) { return std::abs(got - expected) <= 1e-9 * std::abs(expected) + 1e-12; }

/// A box of voxels of kKinds kinds (unmeasured, free, occupied, marked, measured unknown): up to
/// 6 voxels per axis, each of any kind; or (blocks) up to 12, in boxes of one kind; or (sparse)
/// up to 24, all unmeasured but for up to four.
struct KindBox {
  nbv::kernels::SnapshotView view;
  std::vector<std::uint32_t> kind;
  std::vector<std::size_t> others;  ///< sparse: the voxels of another kind
  bool sparse = false;
  int n[3] = {0, 0, 0};

  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * view.size[1] + static_cast<std::size_t>(y)) * view.size[0] +
           static_cast<std::size_t>(x);
  }
  std::uint32_t kindAt(int x, int y, int z) const {  // outside the box every voxel is kind 0
    const bool inside = x >= 0 && y >= 0 && z >= 0 && x < n[0] && y < n[1] && z < n[2];
    return inside ? kind[index(x, y, z)] : 0u;
  }
};

constexpr std::uint32_t kKinds = 5;

KindBox readBox(Bytes& in, bool sparse, bool blocks) {
  KindBox box;
  box.sparse = sparse;
  for (int a = 0; a < 3; ++a) {
    box.view.min[a] = static_cast<int>(in.next() % 16) - 8;
    box.view.size[a] = 1 + in.next() % (sparse ? 24 : blocks ? 12 : 6);
    box.n[a] = static_cast<int>(box.view.size[a]);
  }
  const std::size_t count = std::size_t{box.view.size[0]} * box.view.size[1] * box.view.size[2];
  box.kind.assign(count, 0);
  if (sparse) {
    for (int n = in.next() % 5; n > 0; --n) {
      const std::size_t at = (in.next() | std::size_t{in.next()} << 8) % count;
      box.kind[at] = 1 + in.next() % (kKinds - 1);
      box.others.push_back(at);
    }
  } else if (blocks) {
    for (int b = in.next() % 7; b > 0; --b) {
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = in.next() % box.n[a];
        hi[a] = std::min(box.n[a] - 1, lo[a] + in.next() % box.n[a]);
      }
      const std::uint32_t k = in.next() % kKinds;
      for (int z = lo[2]; z <= hi[2]; ++z) {
        for (int y = lo[1]; y <= hi[1]; ++y) {
          for (int x = lo[0]; x <= hi[0]; ++x) box.kind[box.index(x, y, z)] = k;
        }
      }
    }
  } else {
    for (auto& k : box.kind) k = in.next() % kKinds;
  }
  return box;
}

/// The run distance of voxel (x, y, z) in octant `o` (steps s): the side of the largest cube
/// ahead of it of its own kind, capped.
int runDistanceOf(const KindBox& box, int x, int y, int z, const int s[3]) {
  const int cap = static_cast<int>(nbv::kernels::kMaxRunDistance);
  const std::uint32_t k = box.kindAt(x, y, z);
  if (box.sparse) {
    // Unmeasured voxels: the nearest other voxel ahead decides; the others: 1, which never
    // claims too much.
    int d = k != 0 ? 1 : cap;
    for (const std::size_t at : box.others) {
      const int w[3] = {static_cast<int>(at % box.view.size[0]), static_cast<int>(at / box.view.size[0] % box.view.size[1]),
                        static_cast<int>(at / box.view.size[0] / box.view.size[1])};
      const int ahead[3] = {(w[0] - x) * s[0], (w[1] - y) * s[1], (w[2] - z) * s[2]};
      if (ahead[0] >= 0 && ahead[1] >= 0 && ahead[2] >= 0) d = std::min(d, std::max({ahead[0], ahead[1], ahead[2], 1}));
    }
    return d;
  }
  // Grow the cube one shell at a time. A kind-0 cube longer than the box along every axis holds
  // every voxel of the box ahead of it already: only kind 0 lies beyond.
  const int longest = std::max({box.n[0], box.n[1], box.n[2]});
  int side = 1;
  while (side < cap) {
    bool uniform = true;
    for (int c = 0; c <= side && uniform; ++c) {
      for (int b = 0; b <= side && uniform; ++b) {
        for (int a = 0; a <= side && uniform; ++a) {
          if (std::max({a, b, c}) == side) uniform = box.kindAt(x + s[0] * a, y + s[1] * b, z + s[2] * c) == k;
        }
      }
    }
    if (!uniform) break;
    ++side;
    if (k == 0 && side > longest) side = cap;
  }
  return side;
}

/// The snapshot entries of the box: each voxel's kind (its palette index) and run distances.
std::vector<SnapshotEntry> entriesOf(const KindBox& box) {
  std::vector<SnapshotEntry> voxels(box.kind.size());
  for (int z = 0; z < box.n[2]; ++z) {
    for (int y = 0; y < box.n[1]; ++y) {
      for (int x = 0; x < box.n[0]; ++x) {
        SnapshotEntry entry = box.kind[box.index(x, y, z)];
        for (unsigned o = 0; o < nbv::kernels::kOctants; ++o) {
          const int s[3] = {(o & 1) != 0 ? -1 : 1, (o & 2) != 0 ? -1 : 1, (o & 4) != 0 ? -1 : 1};
          entry = nbv::kernels::withRunDistance(entry, o, static_cast<unsigned>(runDistanceOf(box, x, y, z, s)));
        }
        voxels[box.index(x, y, z)] = entry;
      }
    }
  }
  return voxels;
}

/// Every instruction set's walk gives the scalar walk's sums and counts bit for bit, and the
/// scalar walk the voxel-by-voxel sum over OctoMap's keys.
void checkWalks(const Eigen::Vector3f& origin, const std::vector<Eigen::Vector3f>& ends,
                const nbv::kernels::VoxelLattice& lattice, const nbv::kernels::SnapshotView& view) {
  using nbv::fuzz::check;
  std::vector<RaySums> scalar(ends.size()), packet(ends.size());
  std::vector<RayCounts> scalar_counts(ends.size()), packet_counts(ends.size());
  nbv::kernels::walkRays(origin, ends, lattice, view, nbv::kernels::Isa::Scalar, scalar, scalar_counts);
  for (nbv::kernels::Isa isa : nbv::kernels::availableIsas()) {
    if (isa == nbv::kernels::Isa::Scalar) continue;
    nbv::kernels::walkRays(origin, ends, lattice, view, isa, packet);
    for (std::size_t i = 0; i < ends.size(); ++i) check(sameSums(scalar[i], packet[i]), "scalar == packet walk, bit for bit");
    nbv::kernels::walkRays(origin, ends, lattice, view, isa, packet, packet_counts);
    for (std::size_t i = 0; i < ends.size(); ++i) {
      check(sameSums(scalar[i], packet[i]), "scalar == packet walk with counts, bit for bit");
      check(scalar_counts[i].unknown == packet_counts[i].unknown && scalar_counts[i].frontier == packet_counts[i].frontier,
            "scalar == packet walk: the counts");
    }
  }
  for (std::size_t i = 0; i < ends.size(); ++i) {
    const RaySums expected = nbv::test::sumOverOctomapKeys(origin, ends[i], lattice, view);
    const RaySums& got = scalar[i];
    if (got.voxels != expected.voxels || !near(got.entropy, expected.entropy) || !near(got.oa, expected.oa) ||
        !near(got.uv, expected.uv) || !near(got.rse, expected.rse) || !near(got.pc, expected.pc) ||
        got.end_occupied != expected.end_occupied || got.rear_side != expected.rear_side || got.area != expected.area) {
      std::fprintf(stderr, "ray %zu: voxels %u vs %u, entropy %.17g vs %.17g, oa %.17g vs %.17g\n", i, got.voxels,
                   expected.voxels, got.entropy, expected.entropy, got.oa, expected.oa);
      check(false, "kernel == voxel-by-voxel sum over OctoMap's keys");
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace flag = nbv::kernels::voxel_flag;
  Bytes in{data, size};
  static const float kResolutions[] = {0.05f, 0.01f, 0.125f, 0.1f};
  const std::uint8_t setup = in.next();
  const float resolution = kResolutions[setup % 4];
  // Far points: rays of up to ~3,500 voxels, whose closed forms before and after the box pass
  // 1022 voxels (where 2^-n leaves the normal doubles).
  const int reach = (setup & 8) != 0 ? 64 : 1;
  const nbv::kernels::VoxelLattice lattice(resolution);
  KindBox box = readBox(in, (setup & 4) != 0, (setup & 32) != 0);
  const std::vector<SnapshotEntry> voxels = entriesOf(box);
  // The kinds' terms: an unmeasured voxel, a free one, an occupied one, a marked one (a frontier
  // voxel beside a free one when the setup says so: its count, not its terms, differs), a
  // measured unknown one (P = 0.45).
  const double h12 = nbv::kernels::entropyNats(0.12), h97 = nbv::kernels::entropyNats(0.97);
  const double h45 = nbv::kernels::entropyNats(0.45);
  const std::uint64_t frontier = (setup & 16) != 0 ? flag::kFrontier : 0;
  const VoxelTerms palette[] = {{std::log(2.0), 0.5, 0.0, flag::kUnknown},
                                {h12, 0.88, 0.0, flag::kFree | flag::kMeasured},
                                {h97, 0.03, 0.0, flag::kStop | flag::kOccupied | flag::kMeasured},
                                {std::log(2.0), 0.5, 3.0, flag::kUnknown | flag::kMarked | frontier},
                                {h45, 0.55, 0.0, flag::kUnknown | flag::kMeasured}};
  static_assert(std::size(palette) == kKinds);
  box.view.voxels = voxels.data();
  box.view.palette = palette;

  // One origin, up to 16 rays (more than an 8-lane packet holds, so packets follow each other,
  // the last often part-filled).
  const Eigen::Vector3f origin = point(in, resolution, reach);
  std::vector<Eigen::Vector3f> ends;
  while (ends.size() < 16 && in.at < in.size) ends.push_back(point(in, resolution, reach));
  if (!ends.empty()) checkWalks(origin, ends, lattice, box.view);
  return 0;
}
