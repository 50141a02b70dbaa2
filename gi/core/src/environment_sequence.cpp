#include "nestlight/gi/environment_sequence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <regex>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// The pattern's file name split around its one integer conversion: prefix, width (0: any), suffix.
bool splitPattern(const std::string& name, std::string& prefix, int& width, std::string& suffix) {
  const std::regex conversion("%(0?([0-9]*))d");
  std::smatch m;
  if (!std::regex_search(name, m, conversion)) return false;
  prefix = m.prefix().str();
  suffix = m.suffix().str();
  width = m[2].length() ? std::stoi(m[2].str()) : 0;
  return suffix.find('%') == std::string::npos && prefix.find('%') == std::string::npos;
}

}  // namespace

EnvironmentSequence::EnvironmentSequence(EnvironmentSequenceSpec spec) : spec_(std::move(spec)) {
  const std::string source = spec_.source.string();
  if (!(spec_.fps > 0) || !std::isfinite(spec_.fps))
    throw Error(source, "", "the frame rate must be positive, got " + std::to_string(spec_.fps));
  spec_.cacheFrames = std::max<size_t>(spec_.cacheFrames, 1);
  std::error_code ec;
  if (fs::is_directory(spec_.source, ec)) {
    for (const auto& e : fs::directory_iterator(spec_.source)) {
      const std::string ext = lower(e.path().extension().string());
      if (e.is_regular_file() && (ext == ".exr" || ext == ".hdr")) paths_.push_back(e.path());
    }
    std::sort(paths_.begin(), paths_.end());
  } else {
    std::string prefix, suffix;
    int width = 0;
    const fs::path dir =
        spec_.source.has_parent_path() ? spec_.source.parent_path() : fs::path(".");
    if (!splitPattern(spec_.source.filename().string(), prefix, width, suffix))
      throw Error(source, "",
                  "neither a folder nor a file pattern with one %d or %0Nd (e.g. probe_%04d.exr)");
    std::map<long, fs::path> found;
    if (fs::is_directory(dir, ec))
      for (const auto& e : fs::directory_iterator(dir)) {
        const std::string n = e.path().filename().string();
        if (n.size() <= prefix.size() + suffix.size() || n.compare(0, prefix.size(), prefix) != 0 ||
            n.compare(n.size() - suffix.size(), suffix.size(), suffix) != 0)
          continue;
        const std::string digits =
            n.substr(prefix.size(), n.size() - prefix.size() - suffix.size());
        if (digits.empty() || digits.size() > 9 ||
            !std::all_of(digits.begin(), digits.end(), ::isdigit))
          continue;
        if (width > 0 && int(digits.size()) != width) continue;
        found[std::stol(digits)] = e.path();
      }
    if (!found.empty())
      for (long k = found.begin()->first; k <= found.rbegin()->first; ++k) {
        auto it = found.find(k);
        if (it != found.end()) {
          paths_.push_back(it->second);
        } else {
          // The gap's own name, so that asking for it names what is missing.
          char digits[32];
          std::snprintf(digits, sizeof digits, width > 0 ? "%0*ld" : "%*ld", width, k);
          paths_.push_back(dir / (prefix + digits + suffix));
        }
      }
  }
  if (paths_.empty()) throw Error(source, "", "names no environment frames (.exr or .hdr)");
}

size_t EnvironmentSequence::frameAt(double seconds) const {
  if (!(seconds > 0)) return 0;
  const double f = std::floor(seconds * spec_.fps);
  return f >= double(frames() - 1) ? frames() - 1 : size_t(f);
}

std::shared_ptr<const EnvironmentMap> EnvironmentSequence::frame(size_t i) {
  if (i >= frames())
    throw Error(spec_.source.string(), "",
                "frame " + std::to_string(i) + " asked of " + std::to_string(frames()));
  for (size_t k = 0; k < cache_.size(); ++k)
    if (cache_[k].index == i) {
      std::rotate(cache_.begin() + std::ptrdiff_t(k), cache_.begin() + std::ptrdiff_t(k) + 1,
                  cache_.end());
      return cache_.back().map;
    }
  std::shared_ptr<const EnvironmentMap> map;
  try {
    std::error_code ec;
    if (!fs::exists(paths_[i], ec))
      throw Error(paths_[i].string(), "",
                  "frame " + std::to_string(i) + " of the sequence is missing");
    map = std::make_shared<const EnvironmentMap>(
        EnvironmentMap::load(paths_[i].string(), spec_.rotationDegrees, spec_.scale));
    ++reads_;
  } catch (const Error&) {
    ++bad_;
    if (!spec_.keepPreviousOnBadFrame || !lastGood_) throw;
    return lastGood_;  // not cached: a later call tries the file again
  }
  lastGood_ = map;
  if (cache_.size() >= spec_.cacheFrames) cache_.erase(cache_.begin());
  cache_.push_back({i, map});
  return map;
}

}  // namespace nestlight::gi
