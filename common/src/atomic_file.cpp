#include "squeeze/common/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>
#include <vector>

#include <spdlog/spdlog.h>

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

namespace {

std::atomic<int> folder_counter{0};

// ".NAME.squeeze-new-" / ".NAME.squeeze-old-": the prefixes of a folder's staging and old siblings.
std::string sibling_prefix(const fs::path& dir, const char* kind) {
  return "." + dir.filename().string() + ".squeeze-" + kind + "-";
}

// The process id in "PREFIXPID-N", or 0.
pid_t sibling_pid(const std::string& name, const std::string& prefix) {
  if (name.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string rest = name.substr(prefix.size());
  const size_t dash = rest.find('-');
  if (dash == 0 || dash == std::string::npos) return 0;
  for (size_t i = 0; i < dash; ++i)
    if (rest[i] < '0' || rest[i] > '9') return 0;
  try {
    return static_cast<pid_t>(std::stol(rest.substr(0, dash)));
  } catch (const std::exception&) {
    return 0;
  }
}

// Whether process `pid` is running (this process counts as running: its own staging folders are in use).
bool process_alive(pid_t pid) {
  if (pid == ::getpid()) return true;
  return ::kill(pid, 0) == 0 || errno == EPERM;
}

void spdlog_warn_removal(const fs::path& old, const std::error_code& ec) {
  spdlog::warn("{}: could not remove the replaced output: {} (the next run into the same folder removes it)",
               old.string(), ec.message());
}

[[noreturn]] void fail(const fs::path& target, const std::string& what, const std::error_code& ec) {
  throw InputError(target.string() + ": cannot " + what + ": " + ec.message());
}

}  // namespace

FolderReplacement::FolderReplacement(const fs::path& dir) : target_(dir) {
  check_output_folder(dir);
  fs::path p = fs::absolute(dir).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  if (p == p.root_path() || p.filename() == "." || p.filename() == "..")
    throw InputError(dir.string() + ": cannot replace this folder as a whole: name a folder below it");
  dir_ = p;
  const fs::path parent = dir_.parent_path();
  std::error_code ec;
  // Leftovers of killed runs into the same folder. An old folder whose swap was cut short (no
  // folder at dir) is the last complete output: it goes back first.
  const std::string new_prefix = sibling_prefix(dir_, "new"), old_prefix = sibling_prefix(dir_, "old");
  std::vector<fs::path> stale_new, stale_old;
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (pid_t pid = sibling_pid(name, new_prefix); pid > 0 && !process_alive(pid)) stale_new.push_back(it->path());
    if (pid_t pid = sibling_pid(name, old_prefix); pid > 0 && !process_alive(pid)) stale_old.push_back(it->path());
  }
  std::error_code ec2;
  if (!stale_old.empty() && !fs::exists(dir_, ec2)) {
    fs::rename(stale_old.back(), dir_, ec2);
    if (ec2) fail(target_, "restore the output " + stale_old.back().string() + " of an interrupted run", ec2);
    stale_old.pop_back();
  }
  for (const fs::path& q : stale_new) fs::remove_all(q, ec2);
  for (const fs::path& q : stale_old) fs::remove_all(q, ec2);

  staging_ = parent / (new_prefix + std::to_string(::getpid()) + "-" + std::to_string(++folder_counter));
  fs::remove_all(staging_, ec);
  fs::create_directory(staging_, ec);
  if (ec) fail(target_, "create the folder " + staging_.string(), ec);
}

FolderReplacement::~FolderReplacement() {
  std::error_code ec;
  if (!committed_) fs::remove_all(staging_, ec);
}

void FolderReplacement::commit() {
  if (committed_) throw std::logic_error("FolderReplacement::commit: called twice");
  std::error_code ec;
  const bool had_old = fs::is_directory(dir_, ec);
  if (!had_old) {
    fs::rename(staging_, dir_, ec);
    if (ec) fail(target_, "move the new output into place", ec);
    committed_ = true;
    return;
  }
  // Carry over what the new output does not replace, as hard links (the old folder stays complete).
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path to = staging_ / it->path().filename();
    std::error_code e;
    if (fs::exists(fs::symlink_status(to, e))) continue;
    if (it->path().filename().string().rfind(".trajectory.tmp-", 0) == 0) continue;  // leftovers of older versions
    const auto opts = fs::copy_options::recursive | fs::copy_options::copy_symlinks;
    fs::copy(it->path(), to, opts | fs::copy_options::create_hard_links, e);
    if (e) {
      fs::remove_all(to, e);
      e.clear();
      fs::copy(it->path(), to, opts, e);
      if (e) fail(target_, "carry " + it->path().string() + " over into the new output", e);
    }
  }
  if (ec) fail(target_, "list the old output", ec);
  // The swap: one atomic exchange where the file system has it.
  if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, dir_.c_str(), RENAME_EXCHANGE) == 0) {
    committed_ = true;
    fs::remove_all(staging_, ec);  // the old content
    if (ec) spdlog_warn_removal(staging_, ec);
    return;
  }
  const int err = errno;
  if (err != EINVAL && err != ENOSYS && err != ENOTSUP)
    fail(target_, "swap in the new output", std::error_code(err, std::generic_category()));
  const fs::path old = dir_.parent_path() / (sibling_prefix(dir_, "old") + std::to_string(::getpid()) + "-" +
                                              std::to_string(++folder_counter));
  fs::rename(dir_, old, ec);
  if (ec) fail(target_, "move the old output aside", ec);
  fs::rename(staging_, dir_, ec);
  if (ec) {
    std::error_code e;
    fs::rename(old, dir_, e);
    fail(target_, "move the new output into place", ec);
  }
  committed_ = true;
  fs::remove_all(old, ec);
  if (ec) spdlog_warn_removal(old, ec);
}

}  // namespace squeeze
