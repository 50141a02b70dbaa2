// Progress on long work: phase, rate and ETA on a terminal; JSON lines for scripts and servers.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace nestlight {

enum class ProgressMode { Auto, Terminal, Json, Quiet };

// A phase prints nothing when it begins: its first line comes once it has done some work and a
// rate can be measured (a quarter of a second on a terminal, 2 s in JSON), and its last when it
// ends. Each phase shows one rate in one unit throughout: points/s for the phases that read the
// input (they count bytes, which every format knows the size of, but users think in points),
// else the phase's own unit. With a plan() the ETA is the whole job's, across the phases still to
// run; without one, the current phase's.
class Progress {
 public:
  // Seconds on a steady clock; tests pass their own.
  using Clock = std::function<double()>;
  explicit Progress(ProgressMode mode = ProgressMode::Auto, std::FILE* out = stderr,
                    Clock now = {});
  // The phases the job runs, in order, each with the share of the job's time it is expected to
  // take (any scale). The overall ETA projects the remaining phases from the measured ones,
  // scaled by their shares. A planned phase that never begins (one after it begins first) drops
  // out; a phase that is not planned has an ETA of its own only.
  void plan(const std::vector<std::pair<std::string, double>>& phases);
  // Starts a phase whose work is `total` units of `unit` ("points", "bytes", "levels").
  void begin(const std::string& phase, uint64_t total, const std::string& unit);
  // Thread-safe; prints at most a few times a second. `points` counts points handled, for the
  // points/s rate of phases measured in bytes.
  void advance(uint64_t units, uint64_t points = 0);
  void end();
  // A line outside the progress display (warnings).
  void message(const std::string& text);

 private:
  struct Planned {
    std::string name;
    double weight = 0;
    enum State { Pending, Running, Done, Skipped } state = Pending;
    double seconds = 0;  // measured, once done
  };
  void print(bool final);
  double now() const;
  // Seconds left in the current phase and, with a plan, in the whole job; < 0: not measurable.
  double phaseEta(double elapsed) const;
  double overallEta(double elapsed) const;
  ProgressMode mode_;
  std::FILE* out_;
  Clock clock_;
  std::chrono::steady_clock::time_point epoch_;
  std::mutex mutex_;
  std::string phase_, unit_;
  uint64_t total_ = 0, done_ = 0, points_ = 0;
  double start_ = 0, last_ = 0;
  bool open_ = false;
  std::vector<Planned> plan_;
  int current_ = -1;  // index in plan_ of the running phase, -1: not planned
};

}  // namespace nestlight
