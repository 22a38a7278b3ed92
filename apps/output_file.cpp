#include "output_file.hpp"

#include "nbv/errors.hpp"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <system_error>

#include <unistd.h>

namespace nbv::apps {

namespace fs = std::filesystem;

namespace {

/// Where the file written to "-" goes: standard output, or its duplicate once
/// reserveStandardOutput() has sent the reports to standard error.
int standard_output = STDOUT_FILENO;

std::string systemError() { return std::strerror(errno); }

}  // namespace

void reserveStandardOutput() {
  std::fflush(stdout);
  std::cout.flush();
  const int kept = ::dup(STDOUT_FILENO);
  if (kept < 0 || ::dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
    throw FileError(fs::path(kStandardOutput), "cannot keep standard output for the file: " + systemError());
  }
  standard_output = kept;
}

void checkWritable(const fs::path& path) {
  if (path.empty()) throw FileError(path, "no output file named");
  if (path == kStandardOutput) return;
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

/// Where `path` is written before it is complete: beside it (renamed over it), or for "-" in
/// the temporary folder (copied to standard output).
fs::path temporaryFor(const fs::path& path) {
  static std::atomic<unsigned> count{0};
  if (path == kStandardOutput) {
    return fs::temp_directory_path() / ("nbv-stdout-" + std::to_string(::getpid()) + "-" + std::to_string(count++));
  }
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "." + std::string&&.
  std::string name = ".";
  name += path.filename().string();
  name += ".tmp-";
  name += std::to_string(::getpid());
  return path.parent_path() / name;
}

/// The bytes of the complete file `temporary` to standard output.
void copyToStandardOutput(const fs::path& temporary) {
  std::ifstream in(temporary, std::ios::binary);
  if (!in) throw FileError(fs::path(kStandardOutput), "cannot read back the file written for standard output");
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    for (std::streamsize done = 0; done < in.gcount();) {
      const ssize_t n = ::write(standard_output, buffer + done, static_cast<std::size_t>(in.gcount() - done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw FileError(fs::path(kStandardOutput), "cannot write to standard output: " + systemError());
      done += n;
    }
  }
}

}  // namespace

void writeAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  checkWritable(path);
  const bool to_standard_output = path == kStandardOutput;
  const fs::path temporary = temporaryFor(path);
  try {
    write(temporary);
    std::error_code ec;
    if (to_standard_output) {
      copyToStandardOutput(temporary);
      fs::remove(temporary, ec);
    } else {
      fs::rename(temporary, path, ec);
      if (ec) throw FileError(path, "cannot replace file: " + ec.message());
    }
  } catch (const std::exception& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    // The temporary is an implementation detail: the user named `path`.
    throw std::runtime_error(replaced(e.what(), temporary.string(), to_standard_output ? "standard output" : path.string()));
  }
}

}  // namespace nbv::apps
