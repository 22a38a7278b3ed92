#include "output_file.hpp"

#include <stdexcept>
#include <string>
#include <system_error>

#include <unistd.h>

namespace nbv::apps {

void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write) {
  namespace fs = std::filesystem;
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "." + std::string&&.
  std::string name = ".";
  name += path.filename().string();
  name += ".tmp-";
  name += std::to_string(::getpid());
  const fs::path temporary = path.parent_path() / name;
  try {
    write(temporary);
    std::error_code ec;
    fs::rename(temporary, path, ec);
    if (ec) throw std::runtime_error(path.string() + ": cannot replace file: " + ec.message());
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
}

}  // namespace nbv::apps
