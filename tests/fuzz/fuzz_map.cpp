// Map files (the first byte picks .ot, .bt or .vdb): read or refused with MapFileError; a map
// read has counts that add up and probabilities in [0, 1]. (.vdb joined once nbv
// checked every length inside a grid before OpenVDB reads it: tests/fuzz/findings.)
#include "fuzz_input_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".ot", ".bt", ".vdb"};
  const auto path = nbv::fuzz::writeInput(data + 1, size - 1, kExtensions[data[0] % 3]);
  try {
    // A map of pruned nodes may hold billions of voxels in a few tiles: within a cap of 64 MB,
    // the classes' counts add up, and a map small enough to list has that many voxels, each
    // with a probability in [0, 1].
    nbv::grid::MapLoadOptions options;
    options.max_bytes = std::size_t{64} << 20;
    const nbv::grid::OccupancyMap map = nbv::grid::loadMap(path, options);
    const std::size_t measured = map.measuredCount();
    nbv::fuzz::check(map.occupiedCount() + map.freeCount() <= measured, "class counts within the measured count");
    if (measured <= (std::size_t{1} << 22)) {
      const auto voxels = map.measuredVoxels();
      nbv::fuzz::check(voxels.size() == measured, "measured count");
      for (const auto& v : voxels) {
        const double p = map.probability(v.ijk);
        nbv::fuzz::check(p >= 0.0 && p <= 1.0, "probabilities in [0, 1]");
      }
    }
  } catch (const nbv::MapFileError&) {
  }
  return 0;
}
