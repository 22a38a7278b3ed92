// Side-by-side timing of builds of the kernels library (A/B), for changes to the IG walks.
//
//   nbv_ab_kernels ISA ROUNDS RAYS LIBRARY...
//
// ISA: avx512 | avx2 | scalar; RAYS: full (every 8th view of bunny-3, as nbv_bench_ig) |
// released (all 48 views). Each LIBRARY is a copy of a build's libnbv_kernels.so, loaded on its
// own (dlopen, RTLD_LOCAL | RTLD_DEEPBIND), so that every copy walks the same rays on the same
// snapshot in one process. Each round walks every view once with every library, in an order
// that rotates per view and round, so that a busy moment of the machine falls on all of them
// alike; per library it prints the fastest round, the lower quartile and the median, and the
// voxels walked (equal for builds that agree). Needs `make models`.
#include "nbv/grid/information_gain.hpp"
#include "nbv/grid/map_snapshot.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using WalkRays = void (*)(const Eigen::Vector3f&, std::span<const Eigen::Vector3f>, const nbv::kernels::VoxelLattice&,
                          const nbv::kernels::SnapshotView&, nbv::kernels::Isa, std::span<nbv::kernels::RaySums>);

/// nbv::kernels::walkRays() of the library at `path`, loaded apart from every other copy.
WalkRays loadWalk(const std::string& path) {
  void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
  if (library == nullptr) throw std::runtime_error(dlerror());  // (names the file)
  // The mangled name of nbv::kernels::walkRays(origin, ends, lattice, view, isa, out).
  const char* name =
      "_ZN3nbv7kernels8walkRaysERKN5Eigen6MatrixIfLi3ELi1ELi0ELi3ELi1EEESt4spanIS4_Lm18446744073709551615EERKNS0_"
      "12VoxelLatticeERKNS0_12SnapshotViewENS0_3IsaES6_INS0_7RaySumsELm18446744073709551615EE";
  void* walk = dlsym(library, name);
  if (walk == nullptr) throw std::runtime_error(path + " has no nbv::kernels::walkRays() of this signature");
  return reinterpret_cast<WalkRays>(walk);
}

nbv::kernels::Isa isaNamed(const std::string& name) {
  if (name == "avx512") return nbv::kernels::Isa::Avx512;
  if (name == "avx2") return nbv::kernels::Isa::Avx2;
  if (name == "scalar") return nbv::kernels::Isa::Scalar;
  throw std::runtime_error("unknown instruction set '" + name + "' (avx512, avx2 or scalar)");
}

int run(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s avx512|avx2|scalar ROUNDS full|released LIBRARY...\n", argv[0]);
    return 2;
  }
  const nbv::kernels::Isa isa = isaNamed(argv[1]);
  const int rounds = std::atoi(argv[2]);
  if (rounds < 1) throw std::runtime_error(std::string("ROUNDS must be a positive number, not '") + argv[2] + "'");
  const std::string rays = argv[3];
  if (rays != "full" && rays != "released") throw std::runtime_error("RAYS must be full or released, not '" + rays + "'");
  std::vector<std::string> names(argv + 4, argv + argc);
  std::vector<WalkRays> walks;
  for (const std::string& name : names) walks.push_back(loadWalk(name));

  const nbv::planner::Workload workload = nbv::planner::makeWorkload("bunny-3", NBV_BENCH_MODELS_DIR);
  const nbv::grid::EvaluateOptions options;
  nbv::grid::MapSnapshot snapshot;
  snapshot.update(workload.map, options.voxelModel(workload.map.config()), options.max_snapshot_bytes);
  const nbv::kernels::SnapshotView view = snapshot.view();
  const std::vector<Eigen::Vector3d> directions = nbv::grid::coherentOrder(nbv::sensor::rayDirectionsCamera(
      nbv::sensor::PinholeCamera{}, nbv::sensor::PixelSampling::fromName(rays)));
  // As IgEvaluator walks them: a view's rays in blocks of rays_per_task.
  const std::size_t every = rays == "full" ? 8 : 1;
  std::vector<Eigen::Isometry3d> views;
  std::vector<std::vector<Eigen::Vector3f>> ends;
  for (std::size_t v = 0; v < workload.candidates.size(); v += every) {
    views.push_back(workload.candidates[v].T_world_camera);
    ends.emplace_back();
    for (const Eigen::Vector3d& d : directions) ends.back().push_back(nbv::grid::igRay(views.back(), d, options.max_ray_depth).end);
  }
  std::vector<nbv::kernels::RaySums> sums(options.rays_per_task);
  std::vector<std::vector<double>> round_ms(walks.size());
  std::vector<std::uint64_t> voxels(walks.size(), 0);
  for (int round = 0; round < rounds; ++round) {
    std::vector<double> ms(walks.size(), 0.0);
    for (std::size_t v = 0; v < views.size(); ++v) {
      const Eigen::Vector3f origin = views[v].translation().cast<float>();
      for (std::size_t k = 0; k < walks.size(); ++k) {
        const std::size_t w = (k + v + static_cast<std::size_t>(round)) % walks.size();
        const auto start = std::chrono::steady_clock::now();
        for (std::size_t first = 0; first < ends[v].size(); first += options.rays_per_task) {
          const std::size_t count = std::min(options.rays_per_task, ends[v].size() - first);
          walks[w](origin, std::span<const Eigen::Vector3f>(ends[v].data() + first, count), workload.map.lattice(), view,
                   isa, std::span<nbv::kernels::RaySums>(sums.data(), count));
          if (round == 0) {
            for (std::size_t i = 0; i < count; ++i) voxels[w] += sums[i].voxels;
          }
        }
        ms[w] += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      }
    }
    for (std::size_t w = 0; w < walks.size(); ++w) round_ms[w].push_back(ms[w]);
  }
  std::printf("%zu views, %zu rays each, %d rounds; ms per round:\n", views.size(), directions.size(), rounds);
  const double first_fastest = *std::min_element(round_ms[0].begin(), round_ms[0].end());
  for (std::size_t w = 0; w < walks.size(); ++w) {
    std::vector<double> ms = round_ms[w];
    std::sort(ms.begin(), ms.end());
    std::printf("%-32s fastest %8.2f  lower quartile %8.2f  median %8.2f  fastest / first's %.4f  voxels %llu\n",
                names[w].c_str(), ms.front(), ms[ms.size() / 4], ms[ms.size() / 2], ms.front() / first_fastest,
                static_cast<unsigned long long>(voxels[w]));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "nbv_ab_kernels: %s\n", e.what());
    return 1;
  }
}
