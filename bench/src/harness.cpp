// What every benchmark harness shares (harness.h).
#include "nestlight/bench/harness.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdarg>
#include <fstream>
#include <thread>

#include "nestlight/octree/error.h"

extern char** environ;

namespace nestlight::bench {

namespace fs = std::filesystem;

void say(std::FILE* log, const char* format, ...) {
  if (!log) return;
  va_list args;
  va_start(args, format);
  std::vfprintf(log, format, args);
  va_end(args);
  std::fflush(log);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()
             ? 0
             : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

std::string cpuName() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

std::string humanBytes(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024 && u < 4) b /= 1024, ++u;
  char buf[32];
  std::snprintf(buf, sizeof buf, u ? "%.1f %s" : "%.0f %s", b, units[u]);
  return buf;
}

std::string humanCount(double n) {
  char buf[32];
  if (n >= 1e9)
    std::snprintf(buf, sizeof buf, "%.2f G", n / 1e9);
  else if (n >= 1e6)
    std::snprintf(buf, sizeof buf, "%.2f M", n / 1e6);
  else if (n >= 1e3)
    std::snprintf(buf, sizeof buf, "%.1f k", n / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.0f", n);
  return buf;
}

namespace {

size_t codePoints(const std::string& s) {
  size_t n = 0;
  for (char c : s) n += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
  return n;
}

}  // namespace

std::string alignedTable(const std::vector<std::vector<std::string>>& rows,
                         const std::vector<bool>& right) {
  std::vector<size_t> width;
  for (const auto& r : rows)
    for (size_t c = 0; c < r.size(); ++c) {
      if (width.size() <= c) width.resize(c + 1, 0);
      width[c] = std::max(width[c], codePoints(r[c]));
    }
  std::string out;
  auto line = [&](const std::vector<std::string>& r) {
    std::string l;
    for (size_t c = 0; c < width.size(); ++c) {
      const std::string cell = c < r.size() ? r[c] : "";
      const std::string pad(width[c] - codePoints(cell), ' ');
      l += (c ? "  " : "") + (c < right.size() && right[c] ? pad + cell : cell + pad);
    }
    while (!l.empty() && l.back() == ' ') l.pop_back();
    out += l + "\n";
  };
  for (size_t i = 0; i < rows.size(); ++i) {
    line(rows[i]);
    if (i == 0) {
      std::vector<std::string> rule;
      for (size_t w : width) rule.push_back(std::string(w, '-'));
      line(rule);
    }
  }
  return out;
}

namespace {

// Bytes of the files under `dir` (missing: 0).
uint64_t folderBytes(const fs::path& dir) {
  uint64_t total = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) total += it->file_size(ec);
  return total;
}

}  // namespace

ChildRun runChild(const std::vector<std::string>& args, const std::string& watch) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  auto t = std::chrono::steady_clock::now();
  pid_t pid = ::fork();
  if (pid == 0) {
    if (FILE* devnull = std::fopen("/dev/null", "w")) ::dup2(::fileno(devnull), 1);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  int status = 0;
  struct rusage ru {};
  ChildRun r;
  // The converter builds WATCH beside it, in .WATCH.build-PID (octree/staged_directory.h), with its
  // temporary files in chunks.tmp there: sample their size while it runs.
  std::atomic<bool> done{false};
  std::thread watcher;
  if (!watch.empty())
    watcher = std::thread([&] {
      const fs::path w(watch);
      const fs::path tmp = w.parent_path() /
                           ("." + w.filename().string() + ".build-" + std::to_string(pid)) /
                           "chunks.tmp";
      while (!done.load()) {
        r.peakTempBytes = std::max(r.peakTempBytes, folderBytes(tmp));
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
      }
    });
  ::wait4(pid, &status, 0, &ru);
  // Timed before the watcher is joined: its sleep would add up to a quarter of a second.
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  done = true;
  if (watcher.joinable()) watcher.join();
  r.peakRss = static_cast<uint64_t>(ru.ru_maxrss) * 1024;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  return r;
}

std::string runSelf(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> all{"/proc/self/exe"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const fs::path out = log;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid;
  const int rc = posix_spawn(&pid, "/proc/self/exe", &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw Error("", "", "cannot start nestlight expand-hdr");
  int status = 0;
  waitpid(pid, &status, 0);
  std::ifstream in(out);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(out.string(), "", "nestlight expand-hdr failed (its output is in this file)");
  return text;
}

}  // namespace nestlight::bench
