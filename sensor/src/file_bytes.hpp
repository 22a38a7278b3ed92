#pragma once
/// \file Reading a whole input file, with the same refusals for every reader (private header).

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace nbv::sensor::detail {

/// The bytes of the file at `path`. \throws Error(path, problem) if it is missing, a directory
/// (`kind` names what was expected: "a mesh file"), unreadable or empty.
template <class Error>
std::string readWholeFile(const std::filesystem::path& path, const std::string& kind) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw Error(path, "no such file");
  if (std::filesystem::is_directory(status)) throw Error(path, "is a directory, not " + kind);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path, "cannot open for reading");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw Error(path, "read failed");
  if (bytes.empty()) throw Error(path, "file is empty");
  return bytes;
}

}  // namespace nbv::sensor::detail
