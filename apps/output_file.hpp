#pragma once
/// \file Output files of the nbv command: written to a temporary beside the target and renamed
/// over it only when complete, so a failed command never leaves a half-written or damaged file.

#include <filesystem>
#include <functional>

namespace nbv::apps {

/// Refuses, before any work, an output the command could not write: its folder is missing or
/// not writable, or the path is a folder. \throws FileError naming `path` as given.
void checkWritable(const std::filesystem::path& path);

/// Calls `write(temporary_path)`, then renames the temporary to `path`. If `write` throws,
/// the temporary is removed and the error propagates, naming `path` wherever it named the
/// temporary; `path` is untouched.
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write);

}  // namespace nbv::apps
