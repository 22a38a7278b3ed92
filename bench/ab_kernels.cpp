// Side-by-side timing of builds of the kernels library (A/B), for changes to the ray walks.
//
//   nbv_ab_kernels ISA ROUNDS RAYS LIBRARY...
//
// ISA: avx512 | avx2 | scalar. RAYS: walkRays() over the IG rays of bunny-3, full (every 8th
// view, as nbv_bench_ig) or released (all 48 views); or markRays() over the rays of a full
// ideal scan of a sphere (tests/scenes.hpp, as nbv_bench_kernels), five times: mark (camera to
// hits, Store, as the occupancy update) or proximity (hits to 0.3 m beyond, MinStepIndex). Each LIBRARY is a copy of
// a build's libnbv_kernels.so, loaded on its own (dlopen, RTLD_LOCAL | RTLD_DEEPBIND), so
// that every copy runs the same work in one process. Each round runs every unit of work once
// with every library, in an order that rotates per unit and round, so that a busy moment of
// the machine falls on all of them alike; per library it prints the fastest round, the lower
// quartile and the median, and a check of what it computed (voxels walked, or a hash of the
// marked bytes: equal for builds that agree). RAYS full and released need `make models`.
#include "nbv/ig/evaluator.hpp"
#include "nbv/ig/map_snapshot.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/planner/workloads.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include "scenes.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace kernels = nbv::kernels;

/// The function `linked` (a function of the kernels library this program links) in the copy
/// of the library at `path`, loaded apart from every other copy. Its symbol is looked up by
/// the mangled name of the linked function, so a changed signature fails here by name.
template <class F>
F* loadFunction(const std::string& path, F* linked) {
  Dl_info info;
  if (dladdr(reinterpret_cast<void*>(linked), &info) == 0 || info.dli_sname == nullptr) {
    throw std::runtime_error("the linked kernels library has no symbol for a function this program calls");
  }
  void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
  if (library == nullptr) throw std::runtime_error(dlerror());  // (names the file)
  void* function = dlsym(library, info.dli_sname);
  if (function == nullptr) throw std::runtime_error(path + " has no " + info.dli_sname + " of this signature");
  return reinterpret_cast<F*>(function);
}

kernels::Isa isaNamed(const std::string& name) {
  if (name == "avx512") return kernels::Isa::Avx512;
  if (name == "avx2") return kernels::Isa::Avx2;
  if (name == "scalar") return kernels::Isa::Scalar;
  throw std::runtime_error("unknown instruction set '" + name + "' (avx512, avx2 or scalar)");
}

/// Work in units, each run with library `library`; returns the unit's check value.
struct Work {
  std::size_t units = 0;
  std::function<std::uint64_t(std::size_t library, std::size_t unit)> run;
  std::string describe;
};

/// walkRays() over the IG rays of bunny-3: a unit is a view, its rays in blocks of
/// rays_per_task as IgEvaluator walks them; the check counts the voxels walked.
Work igWork(const std::vector<std::string>& libraries, const std::string& rays, kernels::Isa isa) {
  // The overload without WalkOptions: older builds have it too (the paper's metrics, no counts).
  using WalkRays = void (*)(const Eigen::Vector3f&, std::span<const Eigen::Vector3f>, const kernels::VoxelLattice&,
                            const kernels::SnapshotView&, kernels::Isa, std::span<kernels::RaySums>);
  std::vector<WalkRays> walks;
  for (const std::string& path : libraries) walks.push_back(loadFunction(path, static_cast<WalkRays>(&kernels::walkRays)));
  struct Data {
    nbv::planner::Workload workload;
    nbv::ig::SnapshotOptions options;
    nbv::ig::WalkOptions walk;
    nbv::ig::MapSnapshot snapshot;
    std::vector<Eigen::Vector3f> origins;
    std::vector<std::vector<Eigen::Vector3f>> ends;
    std::vector<kernels::RaySums> sums;
  };
  auto d = std::make_shared<Data>(Data{nbv::planner::makeWorkload("bunny-3"), {}, {}, {}, {}, {}, {}});
  d->snapshot.update(d->workload.map, d->options.voxelModel(d->workload.map.config()), d->options.max_snapshot_bytes);
  const std::vector<Eigen::Vector3d> directions = nbv::ig::coherentOrder(nbv::sensor::rayDirectionsCamera(
      nbv::sensor::PinholeCamera{}, nbv::sensor::PixelSampling::fromName(rays)));
  const std::size_t every = rays == "full" ? 8 : 1;
  for (std::size_t v = 0; v < d->workload.candidates.size(); v += every) {
    const Eigen::Isometry3d& view = d->workload.candidates[v].T_world_camera;
    d->origins.push_back(view.translation().cast<float>());
    d->ends.emplace_back();
    for (const Eigen::Vector3d& dir : directions) {
      d->ends.back().push_back(nbv::ig::igRay(view, dir, d->walk.max_ray_depth).end);
    }
  }
  d->sums.resize(d->walk.rays_per_task);
  Work work;
  work.units = d->ends.size();
  work.describe = std::to_string(d->ends.size()) + " views of bunny-3, " + std::to_string(directions.size()) +
                  " rays each (walkRays)";
  work.run = [d, walks, isa](std::size_t library, std::size_t v) {
    const kernels::SnapshotView view = d->snapshot.view();
    const std::vector<Eigen::Vector3f>& ends = d->ends[v];
    std::uint64_t voxels = 0;
    for (std::size_t first = 0; first < ends.size(); first += d->walk.rays_per_task) {
      const std::size_t count = std::min(d->walk.rays_per_task, ends.size() - first);
      walks[library](d->origins[v], std::span<const Eigen::Vector3f>(ends.data() + first, count),
                     d->workload.map.lattice(), view, isa, std::span<kernels::RaySums>(d->sums.data(), count));
      for (std::size_t i = 0; i < count; ++i) voxels += d->sums[i].voxels;
    }
    return voxels;
  };
  return work;
}

/// markRays() over a full ideal scan of a sphere, five units on a cleared box: the rays camera ->
/// hit (Store), or with `proximity` the rays hit -> 0.3 m beyond (MinStepIndex); the check
/// hashes the box's bytes.
Work markWork(const std::vector<std::string>& libraries, kernels::Isa isa, bool proximity) {
  std::vector<decltype(&kernels::markRays)> marks;
  for (const std::string& path : libraries) marks.push_back(loadFunction(path, &kernels::markRays));
  struct Data {
    kernels::VoxelLattice lattice{0.01};
    std::vector<Eigen::Vector3f> camera, hits, beyond;
    kernels::DenseBox box;
    std::vector<std::uint8_t> bytes;
  };
  auto d = std::make_shared<Data>();
  const nbv::test::Sphere sphere{{0.0, 0.0, 0.25}, 0.25};
  const Eigen::Vector3d position(0.6, 0.0, 0.25);
  d->hits = nbv::test::idealScan(sphere, nbv::test::lookAt(position, sphere.centre));
  d->camera = {position.cast<float>()};
  Eigen::Vector3f lo = d->camera[0], hi = d->camera[0];
  for (const Eigen::Vector3f& hit : d->hits) {
    d->beyond.push_back(hit + 0.3f * (hit - d->camera[0]).normalized());
    lo = lo.cwiseMin(d->beyond.back()).cwiseMin(hit);
    hi = hi.cwiseMax(d->beyond.back()).cwiseMax(hit);
  }
  d->box = kernels::DenseBox::around(d->lattice.worldToIndex(lo) - kernels::Index3::Ones(),
                                     d->lattice.worldToIndex(hi) + kernels::Index3::Ones());
  d->bytes.resize(d->box.bytes());
  d->box.data = d->bytes.data();
  Work work;
  work.units = 5;
  work.describe = std::to_string(d->hits.size()) + " rays of a sphere scan, " +
                  (proximity ? "proximity-marked" : "marked") + " 5 times (markRays)";
  work.run = [d, marks, isa, proximity](std::size_t library, std::size_t) {
    const kernels::OutsideSink ignore = [](const kernels::Index3&, std::uint8_t) {};
    std::fill(d->bytes.begin(), d->bytes.end(), std::uint8_t{0});
    if (!proximity) {
      marks[library](d->camera, d->hits, d->lattice, d->box, {kernels::MarkSpec::Mode::Store, 1}, ignore, isa);
    } else {
      marks[library](d->hits, d->beyond, d->lattice, d->box, {kernels::MarkSpec::Mode::MinStepIndex, 0}, ignore, isa);
    }
    std::uint64_t hash = 1469598103934665603ull;  // FNV-1a
    for (std::uint8_t b : d->bytes) hash = (hash ^ b) * 1099511628211ull;
    return hash;
  };
  return work;
}

int run(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s avx512|avx2|scalar ROUNDS full|released|mark|proximity LIBRARY...\n", argv[0]);
    return 2;
  }
  const kernels::Isa isa = isaNamed(argv[1]);
  const int rounds = std::atoi(argv[2]);
  if (rounds < 1) throw std::runtime_error(std::string("ROUNDS must be a positive number, not '") + argv[2] + "'");
  const std::string rays = argv[3];
  const std::vector<std::string> names(argv + 4, argv + argc);
  Work work;
  if (rays == "full" || rays == "released") {
    work = igWork(names, rays, isa);
  } else if (rays == "mark" || rays == "proximity") {
    work = markWork(names, isa, rays == "proximity");
  } else {
    throw std::runtime_error("RAYS must be full, released, mark or proximity, not '" + rays + "'");
  }

  // Unit by unit, every library in an order rotating per unit and round; the unit's time
  // excludes the check (the sums, the hash).
  std::vector<std::vector<double>> round_ms(names.size());
  std::vector<std::uint64_t> check(names.size(), 0);
  for (int round = 0; round < rounds; ++round) {
    std::vector<double> ms(names.size(), 0.0);
    for (std::size_t unit = 0; unit < work.units; ++unit) {
      for (std::size_t k = 0; k < names.size(); ++k) {
        const std::size_t w = (k + unit + static_cast<std::size_t>(round)) % names.size();
        const auto start = std::chrono::steady_clock::now();
        const std::uint64_t value = work.run(w, unit);
        ms[w] += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        if (round == 0) check[w] = check[w] * 31 + value;
      }
    }
    for (std::size_t w = 0; w < names.size(); ++w) round_ms[w].push_back(ms[w]);
  }
  std::printf("%s, %d rounds; ms per round:\n", work.describe.c_str(), rounds);
  const double first_fastest = *std::min_element(round_ms[0].begin(), round_ms[0].end());
  for (std::size_t w = 0; w < names.size(); ++w) {
    std::vector<double> ms = round_ms[w];
    std::sort(ms.begin(), ms.end());
    std::printf("%-32s fastest %8.2f  lower quartile %8.2f  median %8.2f  fastest / first's %.4f  check %llu\n",
                names[w].c_str(), ms.front(), ms[ms.size() / 4], ms[ms.size() / 2], ms.front() / first_fastest,
                static_cast<unsigned long long>(check[w]));
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
