#include "nestlight/octree/staged_directory.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "nestlight/octree/error.h"

namespace nestlight {

namespace fs = std::filesystem;

namespace {

std::string stagingPrefix(const fs::path& finalDir) {
  return "." + finalDir.filename().string() + ".build-";
}

// The process id a staging name ends with, or 0.
pid_t pidOf(const std::string& name, const std::string& prefix) {
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string digits = name.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) return 0;
  return pid_t(std::stol(digits));
}

bool running(pid_t pid) {
  return pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH;
}

fs::path normalised(const fs::path& p) {
  fs::path a = fs::absolute(p).lexically_normal();
  if (!a.has_filename()) a = a.parent_path();  // "out/" names the folder out
  return a;
}

}  // namespace

std::vector<fs::path> staleStagingFolders(const fs::path& finalDir) {
  std::vector<fs::path> out;
  const fs::path dir = normalised(finalDir);
  std::error_code ec;
  const std::string prefix = stagingPrefix(dir);
  for (const auto& e : fs::directory_iterator(dir.parent_path(), ec)) {
    const pid_t pid = pidOf(e.path().filename().string(), prefix);
    if (pid > 0 && !running(pid)) out.push_back(e.path());
  }
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const pid_t pid = pidOf(e.path().filename().string(), ".build-");
    if (pid > 0 && !running(pid)) out.push_back(e.path());
  }
  return out;
}

namespace {

// Recreates `from` at `to` with hard links to its files (no data copied; both names stay valid
// whatever happens next).
void linkTree(const fs::path& from, const fs::path& to) {
  const fs::file_status st = fs::symlink_status(from);
  if (fs::is_symlink(st)) {
    fs::copy_symlink(from, to);
  } else if (fs::is_directory(st)) {
    fs::create_directory(to);
    for (const auto& e : fs::directory_iterator(from)) linkTree(e.path(), to / e.path().filename());
  } else {
    std::error_code ec;
    fs::create_hard_link(from, to, ec);
    if (ec) fs::copy_file(from, to);  // a file system without hard links
  }
}

}  // namespace

StagedDirectory::StagedDirectory(fs::path finalDir,
                                 std::function<bool(const std::string&)> replaced)
    : final_(normalised(finalDir)), replaced_(std::move(replaced)) {
  std::error_code ec;
  if (fs::exists(final_, ec) && !fs::is_directory(final_, ec))
    throw Error(final_.string(), "", "exists and is not a folder");
  fs::create_directories(final_.parent_path());
  for (const fs::path& p : staleStagingFolders(final_)) {
    fs::remove_all(p, ec);
    if (!ec) stale_.push_back(p);
  }
  staging_ = final_.parent_path() / (stagingPrefix(final_) + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);  // ours, from an earlier object of this process
  if (!fs::create_directory(staging_, ec) || ec)
    throw Error(staging_.string(), "", "cannot create the staging folder: " + ec.message());
}

StagedDirectory::~StagedDirectory() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

void StagedDirectory::commit() {
  NL_CHECK(!committed_);
  std::error_code ec;
  if (fs::exists(final_, ec)) {
    for (const auto& e : fs::directory_iterator(final_)) {
      const fs::path to = staging_ / e.path().filename();
      if (!replaced_(e.path().filename().string()) && !fs::exists(fs::symlink_status(to)))
        linkTree(e.path(), to);
    }
    // One atomic exchange: readers see the old folder or the new one, never neither.
    if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, final_.c_str(), RENAME_EXCHANGE) != 0) {
      if (errno != EINVAL && errno != ENOSYS)
        throw Error(final_.string(), "",
                    std::string("cannot put the new folder in place: ") + std::strerror(errno));
      // A file system without the exchange: the old folder steps aside first, for a moment.
      const fs::path aside =
          final_.parent_path() / (stagingPrefix(final_) + std::to_string(::getpid()) + "-old");
      fs::remove_all(aside, ec);
      fs::rename(final_, aside);
      try {
        fs::rename(staging_, final_);
      } catch (...) {
        fs::rename(aside, final_, ec);
        throw;
      }
      fs::rename(aside, staging_, ec);
    }
  } else {
    fs::rename(staging_, final_);
  }
  committed_ = true;
  fs::remove_all(staging_, ec);  // the old content, now under the staging name
}

}  // namespace nestlight
