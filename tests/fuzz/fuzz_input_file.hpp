#pragma once
// The fuzz targets feed nbv's readers through files, as a user does: each input is written to a
// file in a private folder (on tmpfs when there is one) under the extension the target picks.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace nbv::fuzz {

inline std::filesystem::path inputPath(const std::string& extension) {
  static const std::filesystem::path folder = [] {
    const std::filesystem::path base = std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
    std::filesystem::path dir = base / ("nbv-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
  }();
  return folder / ("input" + extension);
}

/// Writes `size` bytes of `data` to the input file with `extension` and returns its path.
inline std::filesystem::path writeInput(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  const std::filesystem::path path = inputPath(extension);
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data),
                                                                 static_cast<std::streamsize>(size));
  return path;
}

/// Stops the fuzzer with a message when an invariant fails.
inline void check(bool ok, const char* invariant) {
  if (!ok) {
    std::fprintf(stderr, "invariant violated: %s\n", invariant);
    std::abort();
  }
}

}  // namespace nbv::fuzz
