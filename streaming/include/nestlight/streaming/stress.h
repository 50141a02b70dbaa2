// The scheduler's stress test, shared by `nestlight stress` and the test suite: random and fast
// camera paths (teleports, fast flights, orbits, stops) over an octree, with a memory store and
// small budgets that change at run time, and a check of every frame.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/streaming/streamer.h"

namespace nestlight {
class OctreeReader;
}

namespace nestlight::streaming {

struct StressOptions {
  uint64_t frames = 5000;  // camera frames (the final stop and drain come on top)
  uint64_t seed = 1;
  Budgets budgets{1'000'000, 24ull << 20, 2ull << 20, 2, 1.0};
  bool varyBudgets = true;      // scale the budgets and the loader count now and then
  uint64_t settleFrames = 600;  // a stopped camera must see the cut complete within this
  double frameMs = 4;           // frame period: update() then sleep for the rest (0: no pacing)
  double maxUpdateMs = 0;       // an update() longer than this is a violation (0: not checked)
  int widthPx = 1280, heightPx = 720;
  // Called every `progressEvery` frames with the frame number (0: never).
  uint64_t progressEvery = 0;
  std::function<void(uint64_t)> progress;
};

struct StressReport {
  uint64_t frames = 0;  // every update(), stops and the final drain included
  uint64_t stops = 0;   // times the camera stopped and the cut had to complete
  uint64_t settleFramesMax = 0, settleFramesMedian = 0;
  double updateMsMax = 0, updateMsMedian = 0, updateMsP99 = 0;  // wall time of update()
  // CPU time of the render thread in update(): wall time above it is time the thread was not
  // running (two cores shared with the loaders), not time it waited for anything.
  double updateCpuMsMax = 0, updateCpuMsMedian = 0, updateCpuMsP99 = 0;
  std::vector<uint64_t> settleFrames;    // per stop: frames until the cut was complete
  uint64_t renderThreadReaderCalls = 0;  // reader calls made inside update(): must be 0
  uint64_t maxResidentBytes = 0;         // seen by the store, at any moment
  uint64_t budgetChanges = 0;
  Streamer::Totals totals;
  std::vector<std::string> violations;  // empty when every check held (first 20 kept)
  uint64_t violationCount = 0;

  bool ok() const { return violationCount == 0; }
  nlohmann::json toJson() const;
};

StressReport runStress(OctreeReader& reader, const StressOptions& options);

}  // namespace nestlight::streaming
