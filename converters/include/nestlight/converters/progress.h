// Progress on long work: phase, rate and ETA on a terminal; JSON lines for scripts and servers.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace nestlight {

enum class ProgressMode { Auto, Terminal, Json, Quiet };

class Progress {
 public:
  explicit Progress(ProgressMode mode = ProgressMode::Auto);
  // Starts a phase whose work is `total` units of `unit` ("points", "bytes", "nodes").
  void begin(const std::string& phase, uint64_t total, const std::string& unit);
  // Thread-safe; prints at most a few times a second. `points` counts points handled, for the
  // points/s rate of phases measured in bytes.
  void advance(uint64_t units, uint64_t points = 0);
  void end();
  // A line outside the progress display (warnings).
  void message(const std::string& text);

 private:
  void print(bool final);
  ProgressMode mode_;
  std::mutex mutex_;
  std::string phase_, unit_;
  uint64_t total_ = 0, done_ = 0, points_ = 0;
  std::chrono::steady_clock::time_point start_, last_;
  bool open_ = false;
};

}  // namespace nestlight
