// PLY clouds: every input is read or refused with CloudFileError; nothing else escapes.
#include "fuzz_input_file.hpp"

#include "nbv/sensor/point_cloud_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nbv::fuzz::writeInput(data, size, ".ply");
  try {
    const std::vector<Eigen::Vector3f> points = nbv::sensor::readPlyCloud(path);
    nbv::fuzz::check(points.size() <= size, "no more points than bytes");
  } catch (const nbv::CloudFileError&) {
  }
  return 0;
}
