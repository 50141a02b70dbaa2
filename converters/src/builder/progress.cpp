#include "nestlight/converters/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

namespace nestlight {

namespace {

// "42 s", "3 min 05 s", "2 h 07 min"; `tenths`: "4.2 s" below 10 s.
std::string progressDuration(double s, bool tenths = false) {
  char buf[48];
  const long t = std::lround(std::max(s, 0.0));
  if (tenths && s < 9.95)
    std::snprintf(buf, sizeof buf, "%.1f s", std::max(s, 0.0));
  else if (t < 60)
    std::snprintf(buf, sizeof buf, "%ld s", t);
  else if (t < 3600)
    std::snprintf(buf, sizeof buf, "%ld min %02ld s", t / 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld h %02ld min", t / 3600, (t % 3600) / 60);
  return buf;
}

// "12.34 M points/s", "850.2 k points/s", "2.5 levels/s".
std::string progressRate(double perSecond, const std::string& unit) {
  char buf[64];
  if (perSecond >= 1e6)
    std::snprintf(buf, sizeof buf, "%.2f M %s/s", perSecond / 1e6, unit.c_str());
  else if (perSecond >= 1e3)
    std::snprintf(buf, sizeof buf, "%.1f k %s/s", perSecond / 1e3, unit.c_str());
  else
    std::snprintf(buf, sizeof buf, "%.1f %s/s", perSecond, unit.c_str());
  return buf;
}

}  // namespace

Progress::Progress(ProgressMode mode, std::FILE* out, Clock now)
    : mode_(mode), out_(out), clock_(std::move(now)), epoch_(std::chrono::steady_clock::now()) {
  if (mode_ == ProgressMode::Auto)
    mode_ = ::isatty(::fileno(out_)) ? ProgressMode::Terminal : ProgressMode::Json;
}

double Progress::now() const {
  if (clock_) return clock_();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - epoch_).count();
}

void Progress::plan(const std::vector<std::pair<std::string, double>>& phases) {
  std::lock_guard<std::mutex> lock(mutex_);
  plan_.clear();
  for (const auto& [name, weight] : phases) plan_.push_back({name, std::max(weight, 0.0)});
  current_ = -1;
}

void Progress::begin(const std::string& phase, uint64_t total, const std::string& unit) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = phase;
  unit_ = unit;
  total_ = total;
  done_ = 0;
  points_ = 0;
  start_ = last_ = now();
  open_ = true;
  current_ = -1;
  for (size_t i = 0; i < plan_.size(); ++i)
    if (plan_[i].name == phase && plan_[i].state == Planned::Pending) {
      // The planned phases before it that did not run will not: they drop out of the ETA.
      for (size_t k = 0; k < i; ++k)
        if (plan_[k].state == Planned::Pending) plan_[k].state = Planned::Skipped;
      plan_[i].state = Planned::Running;
      current_ = int(i);
      break;
    }
  // Nothing is printed yet: no rate can be measured before some work is done.
}

void Progress::advance(uint64_t units, uint64_t points) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ += units;
  points_ += points;
  const double t = now();
  const double interval = mode_ == ProgressMode::Json ? 2.0 : 0.25;
  if (done_ > 0 && t - last_ >= interval) {
    last_ = t;
    print(false);
  }
}

void Progress::end() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!open_) return;
  print(true);
  if (current_ >= 0) {
    plan_[current_].state = Planned::Done;
    plan_[current_].seconds = now() - start_;
  }
  open_ = false;
  current_ = -1;
}

void Progress::message(const std::string& text) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (mode_ == ProgressMode::Quiet) return;
  if (mode_ == ProgressMode::Json) {
    std::fprintf(out_, "%s\n", nlohmann::json({{"message", text}}).dump().c_str());
  } else {
    std::fprintf(out_, "\r\033[K%s\n", text.c_str());
  }
  std::fflush(out_);
}

double Progress::phaseEta(double elapsed) const {
  if (total_ == 0 || done_ == 0 || elapsed <= 0) return -1;
  if (done_ >= total_) return 0;
  const double fraction = double(done_) / double(total_);
  return elapsed / fraction - elapsed;
}

double Progress::overallEta(double elapsed) const {
  const double phaseLeft = phaseEta(elapsed);
  if (current_ < 0 || phaseLeft < 0) return phaseLeft;
  // The seconds a unit of weight takes, measured over the phases done and this one as projected,
  // times the weight of the phases still to come.
  double seconds = elapsed + phaseLeft, weight = plan_[current_].weight, later = 0;
  for (size_t i = 0; i < plan_.size(); ++i) {
    if (plan_[i].state == Planned::Done) seconds += plan_[i].seconds, weight += plan_[i].weight;
    if (plan_[i].state == Planned::Pending && int(i) > current_) later += plan_[i].weight;
  }
  if (weight <= 0) return phaseLeft;
  return phaseLeft + later * seconds / weight;
}

void Progress::print(bool final) {
  if (mode_ == ProgressMode::Quiet) return;
  const double secs = std::max(now() - start_, 0.0);
  const bool measured = done_ > 0 && secs > 0;
  // One unit per phase: the phases that read the input count bytes and show points.
  const bool showPoints = unit_ == "bytes";
  const double rate = measured ? double(done_) / secs : 0;
  const double shown = measured ? double(showPoints ? points_ : done_) / secs : 0;
  const double phaseLeft = final ? 0 : phaseEta(secs);
  const double overallLeft = final ? 0 : overallEta(secs);
  int step = 0, steps = 0;
  for (size_t i = 0; i < plan_.size(); ++i)
    if (plan_[i].state != Planned::Skipped) {
      ++steps;
      if (int(i) <= current_) ++step;
    }
  if (mode_ == ProgressMode::Json) {
    nlohmann::json j = {{"phase", phase_}, {"done", done_}, {"total", total_}, {"unit", unit_},
                        {"seconds", secs}, {"rate", rate},  {"final", final}};
    if (current_ >= 0) j["step"] = step, j["steps"] = steps;
    if (!final && overallLeft >= 0) j["eta"] = overallLeft;
    if (!final && phaseLeft >= 0) j["phase_eta"] = phaseLeft;
    if (showPoints) j["points"] = points_, j["points_per_second"] = shown;
    std::fprintf(out_, "%s\n", j.dump().c_str());
  } else {
    const double pct = total_ ? 100.0 * double(std::min(done_, total_)) / double(total_) : 100.0;
    std::string line = current_ >= 0
                           ? "[" + std::to_string(step) + "/" + std::to_string(steps) + "] "
                           : std::string();
    char head[64];
    std::snprintf(head, sizeof head, "%-10s %5.1f%%", phase_.c_str(), final ? 100.0 : pct);
    line += head;
    if (measured) line += "  " + progressRate(shown, showPoints ? "points" : unit_);
    if (final)
      line += "  in " + progressDuration(secs, true);
    else if (overallLeft >= 0)
      line += "  ETA " + progressDuration(overallLeft) + (current_ >= 0 ? " overall" : "");
    std::fprintf(out_, "\r\033[K%s%s", line.c_str(), final ? "\n" : "");
  }
  std::fflush(out_);
}

}  // namespace nestlight
