// A GI method: anything that renders a scene from a camera into a linear HDR image with the
// reference's conventions (gi::cameraRay's pixels, scene-local frame, radiance per pixel). Made
// by name from the registry (nestlight/gi/methods.h, after pbrt-v4's Integrator::Create), so
// `nestlight render`, `nestlight view`, `bench gi` and the tests run every method the same way.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct MethodFrame {
  HdrImage image;
  double seconds = 0;  // the frame's wall time, loading excluded (GPU work finished)
  // GPU time per pass of the frame (GL methods), in the order the passes ran.
  std::vector<std::pair<std::string, double>> passMs;
  ImageAttributes attributes;  // for the EXR header: "nestlight:*"
  std::string summary;         // one line for the log
  // Sampling methods: samples per pixel, their own error estimate, rays traced.
  int samplesPerPixel = 0;
  double relativeError = 0;
  uint64_t rays = 0;
  uint64_t nonFiniteSamples = 0;
  std::string stopReason;
  double raysPerSecond() const { return seconds > 0 ? double(rays) / seconds : 0; }
  double samplesPerSecond() const {
    return seconds > 0 ? double(samplesPerPixel) * double(image.pixels()) / seconds : 0;
  }
};

class Method {
 public:
  virtual ~Method() = default;
  virtual std::string name() const = 0;
  // One frame from `camera`. Throws nestlight::Error on failure.
  virtual MethodFrame render(const SceneCamera& camera) = 0;

  // Interactive frames (GL methods, in the viewer's window): renders `camera` in the current GL
  // context with whatever is resident (streaming goes on, nothing waits) and returns the GL name
  // of an RGBA8 texture holding the tone-mapped frame (gi/metrics' tone map at exposureStops);
  // `stats` receives the pass timings and summary. 0: the method has no interactive mode.
  virtual unsigned renderInteractive(const SceneCamera& camera, float exposureStops,
                                     MethodFrame* stats) {
    (void)camera, (void)exposureStops, (void)stats;
    return 0;
  }
  // The method's parameters as it resolved them (defaults included), for panels and logs.
  virtual std::vector<std::pair<std::string, std::string>> parameters() const { return {}; }

  // Progressive previews of methods that sample (the path tracer; the viewer accumulates while
  // the camera rests): whether renderBatch works.
  virtual bool rendersInBatches() const { return false; }
  // `samples` more samples per pixel of `camera`, drawn independently of every other `batch`'s
  // (the batch number picks the random sequence), so that the mean of batches 0..n-1 converges as
  // one render of all their samples would. `keepGoing` is asked after every sample per pixel:
  // once it says no the call returns early, its image the mean of the samples done
  // (MethodFrame::samplesPerPixel, at least 1). One caller at a time, which may be a worker thread
  // (nothing else may use the method meanwhile). Methods that do not render in batches return an
  // empty frame.
  virtual MethodFrame renderBatch(const SceneCamera& camera, int samples, uint64_t batch,
                                  const std::function<bool()>& keepGoing) {
    (void)camera, (void)samples, (void)batch, (void)keepGoing;
    return {};
  }
};

// How a method was asked for: progress lines (stderr) unless quiet; GL methods make a headless
// context of their own unless the caller (the viewer's window) has one current.
struct MethodContext {
  MethodContext(bool quietArg = false, bool glContextCurrentArg = false,
                bool syncPassTimingArg = false)
      : quiet(quietArg), glContextCurrent(glContextCurrentArg), syncPassTiming(syncPassTimingArg) {}
  bool quiet = false;
  bool glContextCurrent = false;
  // GL methods: also time each pass between glFinish() calls (attributes
  // nestlight:pass_wall_ms:<pass>), which a CPU rasteriser needs for per-pass figures; costs the
  // overlap of passes. `bench gi` sets it.
  bool syncPassTiming = false;
  // Set-up progress, for a window that shows its last frame while a method builds: what the
  // method is doing and how far along it is (0 to 1). Called on the creating thread, between
  // stages (GL state as the method left it: the callee restores what it changes).
  std::function<void(const std::string& stage, double fraction)> progress;
  void report(const std::string& stage, double fraction) const {
    if (progress) progress(stage, fraction);
  }
};

}  // namespace nestlight::gi
