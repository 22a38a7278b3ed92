#pragma once
/// \file Reading a whole input file, with the same refusals for every reader (private header).

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace nbv::sensor::detail {

/// Refuses, with Error(path, problem), a `path` that is missing, a directory (`kind` names what
/// was expected: "a mesh file") or an empty file.
template <class Error>
void requireInputFile(const std::filesystem::path& path, const std::string& kind) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw Error(path, "no such file");
  if (std::filesystem::is_directory(status)) throw Error(path, "is a directory, not " + kind);
  if (std::filesystem::file_size(path, ec) == 0 && !ec) throw Error(path, "file is empty");
}

/// The bytes of the file at `path`, after requireInputFile(). \throws Error(path, problem) as
/// that does, or if the file cannot be read.
template <class Error>
std::string readWholeFile(const std::filesystem::path& path, const std::string& kind) {
  requireInputFile<Error>(path, kind);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open for reading");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path, "read failed");
  if (bytes.empty()) throw Error(path, "file is empty");
  return bytes;
}

}  // namespace nbv::sensor::detail
