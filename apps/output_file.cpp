#include "output_file.hpp"

#include "nbv/errors.hpp"

#include <stdexcept>
#include <string>
#include <system_error>

#include <unistd.h>

namespace nbv::apps {

namespace fs = std::filesystem;

void checkWritable(const fs::path& path) {
  if (path.empty()) throw FileError(path, "no output file named");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw FileError(path, "is a folder, not a file");
  const fs::path folder = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  if (!fs::is_directory(folder, ec)) throw FileError(path, "cannot write: the folder " + folder.string() + " does not exist");
  if (::access(folder.c_str(), W_OK) != 0) throw FileError(path, "cannot write: the folder " + folder.string() + " is not writable");
}

namespace {

/// `text` with every occurrence of `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

}  // namespace

void writeAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  checkWritable(path);
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
    if (ec) throw FileError(path, "cannot replace file: " + ec.message());
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    // The temporary is an implementation detail: the user named `path`.
    throw std::runtime_error(replaced(e.what(), temporary.string(), path.string()));
  }
}

}  // namespace nbv::apps
