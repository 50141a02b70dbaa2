#include "nestlight/converters/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace nestlight {

Progress::Progress(ProgressMode mode) : mode_(mode) {
  if (mode_ == ProgressMode::Auto)
    mode_ = ::isatty(2) ? ProgressMode::Terminal : ProgressMode::Json;
}

void Progress::begin(const std::string& phase, uint64_t total, const std::string& unit) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = phase;
  unit_ = unit;
  total_ = total;
  done_ = 0;
  points_ = 0;
  start_ = last_ = std::chrono::steady_clock::now();
  open_ = true;
  print(false);
}

void Progress::advance(uint64_t units, uint64_t points) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ += units;
  points_ += points;
  auto now = std::chrono::steady_clock::now();
  double interval = mode_ == ProgressMode::Json ? 2.0 : 0.25;
  if (std::chrono::duration<double>(now - last_).count() >= interval) {
    last_ = now;
    print(false);
  }
}

void Progress::end() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!open_) return;
  print(true);
  open_ = false;
}

void Progress::message(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (mode_ == ProgressMode::Quiet) return;
  if (mode_ == ProgressMode::Json) {
    std::fprintf(stderr, "%s\n", nlohmann::json({{"message", text}}).dump().c_str());
  } else {
    std::fprintf(stderr, "\r\033[K%s\n", text.c_str());
  }
}

void Progress::print(bool final) {
  if (mode_ == ProgressMode::Quiet) return;
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  double rate = secs > 0 ? done_ / secs : 0;
  double eta = (rate > 0 && total_ > done_) ? (total_ - done_) / rate : 0;
  if (mode_ == ProgressMode::Json) {
    nlohmann::json j = {{"phase", phase_}, {"done", done_}, {"total", total_}, {"unit", unit_},
                        {"seconds", secs}, {"rate", rate},  {"eta", eta},      {"final", final}};
    if (points_) j["points"] = points_, j["points_per_second"] = secs > 0 ? points_ / secs : 0.0;
    std::fprintf(stderr, "%s\n", j.dump().c_str());
  } else {
    double pct = total_ ? 100.0 * done_ / total_ : 100.0;
    // Phases that read input count bytes (every format knows its size) but users think in points.
    const bool showPoints = points_ > 0;
    std::fprintf(stderr, "\r\033[K%-10s %5.1f%%  %.2f M %s/s  ETA %.0f s%s", phase_.c_str(), pct,
                 (showPoints ? points_ : done_) / std::max(secs, 1e-9) / 1e6,
                 showPoints ? "points" : unit_.c_str(), eta, final ? "\n" : "");
  }
  std::fflush(stderr);
}

}  // namespace nestlight
