// Video light probes: a sequence of lat-long HDR environment maps played at a frame rate, as the
// HDR video environment maps of Kronander, Dahlin, Jönsson, Kok, Schön and Unger, "Real-time
// video based lighting using GPU raytracing" (2014). Frames are named by a printf pattern
// ("probe_%04d.exr") or are the .exr/.hdr files of a folder in name order. They are read when
// asked for and at most `cacheFrames` are held, so a sequence longer than memory streams.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/environment_map.h"

namespace nestlight::gi {

struct EnvironmentSequenceSpec {
  // A printf pattern with one integer conversion (%d or %0Nd) naming the frames, or a folder.
  std::filesystem::path source;
  double fps = 24;
  float rotationDegrees = 0, scale = 1;
  // What a missing or unreadable frame does: an error naming its file (the default), or the
  // last good frame played again (counted by badFrames()).
  bool keepPreviousOnBadFrame = false;
  size_t cacheFrames = 2;
};

class EnvironmentSequence {
 public:
  // Lists the frames. A pattern's frames run from the smallest number present to the largest;
  // a number missing between them is a frame that fails when asked for (a gap in a capture).
  // Throws nestlight::Error naming the source when it names no frame or fps is not positive.
  explicit EnvironmentSequence(EnvironmentSequenceSpec spec);

  size_t frames() const { return paths_.size(); }
  double fps() const { return spec_.fps; }
  double durationSeconds() const { return double(frames()) / spec_.fps; }
  const std::filesystem::path& framePath(size_t i) const { return paths_.at(i); }
  // The frame shown at `seconds` (floor(seconds * fps)), clamped to the sequence.
  size_t frameAt(double seconds) const;

  // Frame i, read now unless cached. Throws nestlight::Error naming the frame's file when it is
  // missing or unreadable (unless keepPreviousOnBadFrame and a good frame was read before).
  std::shared_ptr<const EnvironmentMap> frame(size_t i);

  size_t cachedFrames() const { return cache_.size(); }
  size_t framesRead() const { return reads_; }
  size_t badFrames() const { return bad_; }

 private:
  EnvironmentSequenceSpec spec_;
  std::vector<std::filesystem::path> paths_;
  struct Cached {
    size_t index;
    std::shared_ptr<const EnvironmentMap> map;
  };
  std::vector<Cached> cache_;  // most recently used last
  std::shared_ptr<const EnvironmentMap> lastGood_;
  size_t reads_ = 0, bad_ = 0;
};

}  // namespace nestlight::gi
