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

namespace {

// A failed write's message as the user should read it: about `target`, not the temporary name,
// and saying so when the disk is full (less than 1 MB left where the target goes).
std::string about_target(std::string what, const fs::path& tmp, const fs::path& target) {
  for (size_t at; (at = what.find(tmp.string())) != std::string::npos;) what.replace(at, tmp.string().size(), target.string());
  std::error_code ec;
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const fs::space_info space = fs::space(dir, ec);
  if (!ec && space.available < (1u << 20) && what.find("disk is full") == std::string::npos)
    what = target.string() + ": the disk is full (" + std::to_string(space.available) + " bytes left in " + dir.string() +
           "): " + what;
  return what;
}

}  // namespace

void write_atomically(const fs::path& target, const std::function<void(const fs::path&)>& write) {
  check_output_directory(target);
  std::error_code ec;
  if (fs::is_directory(target, ec)) throw InputError(target.string() + ": is a directory, not a file");
  const fs::path tmp = temporary_sibling(target);
  try {
    write(tmp);
  } catch (const InputError& e) {
    fs::remove(tmp, ec);
    throw InputError(about_target(e.what(), tmp, target));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string why = ec.message();  // before remove() overwrites ec
    fs::remove(tmp, ec);
    throw InputError(about_target(target.string() + ": cannot write: " + why, tmp, target));
  }
}

}  // namespace squeeze
