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

/// Replaces an output folder as a whole, so that a crash or kill -9 at any moment leaves either the
/// complete old folder or the complete new one (what `simulate`, `replay`, `run` and `render` write):
///
///   FolderReplacement out(dir);          // checks dir, removes leftovers of killed runs
///   write_everything_into(out.staging());
///   out.commit();                        // the swap; without it the destructor removes the staging folder
///
/// The new content is written into a staging folder beside `dir` (same parent, so renames are
/// atomic): PARENT/.NAME.squeeze-new-PID-N. commit() first carries over, as hard links (copies where
/// links fail), the top-level entries of the old folder that the new one does not have (files of other
/// commands, frames of another --frames range), then swaps the two folders with one
/// renameat2(RENAME_EXCHANGE) and deletes the old content (now at the staging name). On a file
/// system without RENAME_EXCHANGE it renames the old folder away (PARENT/.NAME.squeeze-old-PID-N),
/// renames the new one in and deletes the old; a kill between the two renames leaves no `dir`, and
/// the next FolderReplacement of `dir` renames the old folder back before anything else.
/// Leftovers of killed runs (.NAME.squeeze-new-* / .NAME.squeeze-old-* whose process is gone) are
/// removed by the next FolderReplacement of the same `dir`.
/// Errors: InputError ("DIR: exists and is not a directory", "DIR: parent directory P does not
/// exist", "DIR: cannot ...: reason").
class FolderReplacement {
 public:
  explicit FolderReplacement(const std::filesystem::path& dir);
  ~FolderReplacement();
  FolderReplacement(const FolderReplacement&) = delete;
  FolderReplacement& operator=(const FolderReplacement&) = delete;
  /// The folder to write the new content into (exists, empty at first).
  const std::filesystem::path& staging() const { return staging_; }
  /// The folder being replaced, as given.
  const std::filesystem::path& target() const { return target_; }
  /// Moves the new content into place (see above). Throws InputError; after a failure `dir` is the
  /// complete old folder (or missing if it was) and the staging folder is removed by the destructor.
  void commit();

 private:
  std::filesystem::path target_, dir_, staging_;
  bool committed_ = false;
};

/// A temporary path next to `target` that keeps its extension (writers choose the format by it),
/// e.g. out.mesh -> out.tmp-1234-1.mesh.
std::filesystem::path temporary_sibling(const std::filesystem::path& target);

}  // namespace squeeze
