// squeeze::common — write outputs under a temporary name and rename them into place, so that a
// failure (or a crash) never leaves a half-written file behind.
#pragma once
#include <filesystem>
#include <functional>

namespace squeeze {

/// Calls write(tmp) with a temporary path next to `target` (same directory, so the rename is
/// atomic on POSIX file systems), then renames tmp to target. If write throws, the temporary file is
/// removed and the exception propagates; `target` is untouched.
/// Throws InputError if the directory does not exist or is not writable.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path& tmp)>& write);

/// Throws InputError ("TARGET: output directory DIR does not exist" / "is not writable") unless
/// the directory `target` would be written in exists and is writable. Commands call it before any
/// work, so that a bad output path fails fast.
void check_output_directory(const std::filesystem::path& target);

/// The same for a folder a command will create and fill: throws InputError
/// ("DIR: exists and is not a directory" / "DIR: parent directory P does not exist") unless `dir`
/// is an existing directory or a missing one whose parent exists.
void check_output_folder(const std::filesystem::path& dir);

/// A temporary path next to `target` that keeps its extension (writers choose the format by it),
/// e.g. out.mesh -> out.tmp-1234-1.mesh.
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

}  // namespace squeeze
