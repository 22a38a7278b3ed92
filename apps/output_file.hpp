#pragma once
/// \file Output files of the nbv command: written to a temporary beside the target and renamed
/// over it only when complete, so a failed command never leaves a half-written or damaged file.

#include <filesystem>
#include <functional>

namespace nbv::apps {

/// Calls `write(temporary_path)`, then renames the temporary to `path`. If `write` throws,
/// the temporary is removed and the exception propagates; `path` is untouched.
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write);

}  // namespace nbv::apps
