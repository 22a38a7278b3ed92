// Map files (the first byte picks .ot, .bt or .vdb): read or refused with MapFileError; a map
// read has non-negative counts that add up and probabilities in [0, 1]. (.vdb joined once nbv
// checked every length inside a grid before OpenVDB reads it: tests/fuzz/findings.)
#include "fuzz_input_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[] = {".ot", ".bt", ".vdb"};
  const auto path = nbv::fuzz::writeInput(data + 1, size - 1, kExtensions[data[0] % 3]);
  try {
    const nbv::grid::OccupancyMap map = nbv::grid::loadMap(path);
    const auto voxels = map.measuredVoxels();
    nbv::fuzz::check(voxels.size() == map.measuredCount(), "measured count");
    for (const auto& v : voxels) {
      const double p = map.probability(v.ijk);
      nbv::fuzz::check(p >= 0.0 && p <= 1.0, "probabilities in [0, 1]");
    }
  } catch (const nbv::MapFileError&) {
  }
  return 0;
}
