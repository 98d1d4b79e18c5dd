// Crash safety of outputs (issue 20): FolderReplacement (common/atomic_file.h) replaces an output
// folder as a whole, and `squeeze simulate` killed with SIGKILL at random moments while replacing
// an existing output leaves either the complete old output or the complete new one.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fcntl.h>
#include <map>
#include <random>
#include <thread>

#include "meshing_test_util.h"
#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

namespace {
using namespace sqt;
using squeeze::FolderReplacement;

// Every regular file under `dir` (relative path → content): two folders are the same output when
// their listings are equal.
std::map<std::string, std::string> listing(const fs::path& dir) {
  std::map<std::string, std::string> m;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) m[fs::relative(e.path(), dir).generic_string()] = read_text(e.path());
  return m;
}

void write_file(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// Entries of `parent` that are staging or old folders of `name` (".NAME.squeeze-*").
std::vector<std::string> siblings_of(const fs::path& parent, const std::string& name) {
  std::vector<std::string> v;
  for (const auto& e : fs::directory_iterator(parent)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("." + name + ".squeeze-", 0) == 0) v.push_back(n);
  }
  return v;
}

TEST(FolderReplacement, ReplacesTheFolderAndCarriesOverWhatTheNewOneLacks) {
  const TempDir tmp("folder");
  const fs::path out = tmp.path() / "out";
  write_file(out / "metrics.csv", "old");
  write_file(out / "trajectory" / "index.json", "old index");
  write_file(out / "trajectory" / "frames" / "000009.bin", "old frame 9");
  write_file(out / "frames" / "frame_00000.png", "a render of the old trajectory");
  {
    FolderReplacement r(out);
    EXPECT_EQ(r.staging().parent_path(), tmp.path());
    write_file(r.staging() / "metrics.csv", "new");
    write_file(r.staging() / "trajectory" / "index.json", "new index");
    EXPECT_EQ(read_text(out / "metrics.csv"), "old");  // untouched until the swap
    r.commit();
  }
  const auto m = listing(out);
  EXPECT_EQ(m.at("metrics.csv"), "new");
  EXPECT_EQ(m.at("trajectory/index.json"), "new index");
  EXPECT_EQ(m.count("trajectory/frames/000009.bin"), 0u);  // trajectory/ is replaced as a whole
  EXPECT_EQ(m.at("frames/frame_00000.png"), "a render of the old trajectory");  // carried over
  EXPECT_TRUE(siblings_of(tmp.path(), "out").empty());
}

TEST(FolderReplacement, WithoutCommitTheOldFolderStaysAndTheStagingGoes) {
  const TempDir tmp("folder-abort");
  const fs::path out = tmp.path() / "out";
  write_file(out / "metrics.csv", "old");
  {
    FolderReplacement r(out);
    write_file(r.staging() / "metrics.csv", "half");
  }
  EXPECT_EQ(listing(out), (std::map<std::string, std::string>{{"metrics.csv", "old"}}));
  EXPECT_TRUE(siblings_of(tmp.path(), "out").empty());
  // A missing folder is created by the commit only.
  {
    FolderReplacement r(tmp.path() / "fresh");
    EXPECT_FALSE(fs::exists(tmp.path() / "fresh"));
  }
  EXPECT_FALSE(fs::exists(tmp.path() / "fresh"));
}

TEST(FolderReplacement, LeftoversOfKilledRunsAreRemovedAndAnInterruptedSwapIsUndone) {
  const TempDir tmp("folder-leftovers");
  const fs::path out = tmp.path() / "out";
  // A process id above the kernel's pid_max (4194304 at most): a run that is gone.
  write_file(tmp.path() / ".out.squeeze-new-999999999-1" / "metrics.csv", "half-written");
  write_file(tmp.path() / ".out.squeeze-old-999999999-2" / "metrics.csv", "the last complete output");
  write_file(tmp.path() / ".other.squeeze-new-999999999-1" / "x", "another folder's: kept");
  {
    // No `out`: a swap without RENAME_EXCHANGE was cut between its two renames.
    FolderReplacement r(out);
    EXPECT_EQ(read_text(out / "metrics.csv"), "the last complete output");
    EXPECT_EQ(siblings_of(tmp.path(), "out"), std::vector<std::string>{r.staging().filename().string()});
  }
  EXPECT_TRUE(siblings_of(tmp.path(), "out").empty());
  EXPECT_TRUE(fs::exists(tmp.path() / ".other.squeeze-new-999999999-1" / "x"));
}

TEST(FolderReplacement, RefusesAFileAndTheRoot) {
  const TempDir tmp("folder-bad");
  write_file(tmp.path() / "file", "x");
  EXPECT_THROW(FolderReplacement(tmp.path() / "file"), squeeze::InputError);
  EXPECT_THROW(FolderReplacement(tmp.path() / "no" / "such"), squeeze::InputError);
  EXPECT_THROW(FolderReplacement("/"), squeeze::InputError);
}

// Starts `squeeze ARGS` in `cwd` (output to /dev/null) and returns its process id.
pid_t spawn_squeeze(const std::vector<std::string>& args, const fs::path& cwd) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::chdir(cwd.c_str()) != 0) ::_exit(127);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    std::vector<char*> argv;
    const std::string bin = SQUEEZE_BINARY;
    argv.push_back(const_cast<char*>(bin.c_str()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(bin.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

int wait_for(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// The must-show of issue 20: kill -9 at 20 random moments (a fixed seed) while `squeeze simulate`
// replaces an existing output; after each kill the folder is the complete old output or the
// complete new one, and a last run into it leaves no staging or old folder behind.
TEST(CrashSafety, KillNineWhileReplacingAnOutputLeavesTheOldOrTheNewOne) {
  const TempDir tmp("kill9");
  const fs::path& d = tmp.path();
  ::setenv("SQUEEZE_CACHE_DIR", (d / "cache").c_str(), 1);
  const std::string scene = (fs::path(SQUEEZE_SOURCE_DIR) / "scenes" / "cube_drop.json").string();
  const std::vector<std::string> old_args = {"-q", "simulate", scene, "--duration", "0.3", "--fps", "10", "-o"};
  const std::vector<std::string> new_args = {"-q", "simulate", scene, "--duration", "1", "--fps", "120", "-o"};
  auto with = [](std::vector<std::string> a, const std::string& out) {
    a.push_back(out);
    return a;
  };
  ASSERT_EQ(wait_for(spawn_squeeze(with(old_args, "old"), d)), 0);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(wait_for(spawn_squeeze(with(new_args, "new"), d)), 0);
  const double full = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto old_listing = listing(d / "old"), new_listing = listing(d / "new");
  ASSERT_NE(old_listing, new_listing);
  ASSERT_GT(new_listing.size(), 100u);  // 121 frames, the index, rest meshes, metrics.csv

  std::mt19937 random(20);
  std::uniform_real_distribution<double> moment(0.0, 1.1 * full);
  int old_seen = 0, new_seen = 0;
  for (int k = 0; k < 20; ++k) {
    SCOPED_TRACE("kill " + std::to_string(k));
    const fs::path out = d / "out";
    fs::remove_all(out);
    fs::copy(d / "old", out, fs::copy_options::recursive);
    const double at = moment(random);
    const pid_t pid = spawn_squeeze(with(new_args, "out"), d);
    std::this_thread::sleep_for(std::chrono::duration<double>(at));
    ::kill(pid, SIGKILL);
    wait_for(pid);
    ASSERT_TRUE(fs::is_directory(out)) << "no output folder after a kill at " << at << " s";
    const auto now = listing(out);
    const bool is_old = now == old_listing, is_new = now == new_listing;
    EXPECT_TRUE(is_old || is_new) << "a mixed output after a kill at " << at << " s: " << now.size() << " files";
    old_seen += is_old;
    new_seen += is_new;
  }
  std::printf("kill -9 at 20 moments within %.2f s: %d left the old output, %d the new one\n", 1.1 * full, old_seen,
              new_seen);
  // The next run into the same folder removes what killed runs left beside it.
  ASSERT_EQ(wait_for(spawn_squeeze(with(new_args, "out"), d)), 0);
  EXPECT_EQ(listing(d / "out"), new_listing);
  EXPECT_TRUE(siblings_of(d, "out").empty());
}

}  // namespace
