#include "squeeze/common/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <system_error>

#include "squeeze/common/error.h"

namespace squeeze {
namespace fs = std::filesystem;

fs::path temporary_sibling(const fs::path& target) {
  static std::atomic<int> counter{0};
  fs::path tmp = target;
  tmp.replace_filename(target.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                       std::to_string(++counter) + target.extension().string());
  return tmp;
}

void check_output_directory(const fs::path& target) {
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(target.string() + ": output directory " + dir.string() + " does not exist");
  if (::access(dir.c_str(), W_OK) != 0)
    throw InputError(target.string() + ": output directory " + dir.string() + " is not writable");
}

void check_output_folder(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw InputError(dir.string() + ": exists and is not a directory");
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec))
    throw InputError(dir.string() + ": parent directory " + parent.string() + " does not exist");
}

void write_atomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  check_output_directory(target);
  std::error_code ec;
  const fs::path tmp = temporary_sibling(target);
  try {
    write(tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw InputError(target.string() + ": cannot write: " + ec.message());
  }
}

}  // namespace squeeze
