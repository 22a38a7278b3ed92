#pragma once
/// \file Output files of the nbv command: written to a temporary beside the target and renamed
/// over it only when complete, so a failed command never leaves a half-written or damaged file.
/// The output "-" is standard output, which receives the file only once it is complete.

#include <filesystem>
#include <functional>
#include <string_view>

namespace nbv::apps {

/// The output path that names standard output.
inline constexpr std::string_view kStandardOutput = "-";

/// Keeps standard output for the file written to "-": from now on what the command reports
/// (printf, std::cout) goes to standard error. Call once, before the command runs.
/// \throws FileError if the descriptors cannot be duplicated.
void reserveStandardOutput();

/// Refuses, before any work, an output the command could not write: its folder is missing or
/// not writable, or the path is a folder ("-", standard output, is always writable).
/// \throws FileError naming `path` as given.
void checkWritable(const std::filesystem::path& path);

/// Calls `write(temporary_path)`, then renames the temporary to `path`, or for "-" copies it
/// to standard output and removes it. If `write` throws, the temporary is removed and the
/// error propagates, naming `path` wherever it named the temporary; `path` is untouched and
/// nothing reaches standard output.
void writeAtomically(const std::filesystem::path& path,
                     const std::function<void(const std::filesystem::path&)>& write);

}  // namespace nbv::apps
