#include "output_file.hpp"

#include <stdexcept>
#include <string>
#include <system_error>

#include <unistd.h>

namespace nbv::apps {

void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write) {
  namespace fs = std::filesystem;
  const fs::path temporary =
      path.parent_path() / ("." + path.filename().string() + ".tmp-" + std::to_string(::getpid()));
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
