// Progressive previews of the methods that sample (the path tracer, `reference` and `direct`), as
// a path tracer's viewport shows them: a worker thread renders batches of a few samples per pixel
// (gi::Method::renderBatch) into an accumulation buffer that restarts whenever the camera changes;
// the window shows the running mean. On a machine without a GPU this reaches a given error sooner
// than a real-time method's frame does (issue 30), so it is the better preview there.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/scene.h"

namespace nestlight::viewer {

class ProgressiveView {
 public:
  // `method` must render in batches (gi::Method::rendersInBatches). Accumulation stops at
  // `maxSamplesPerPixel` (the scene's gi.samples_per_pixel).
  ProgressiveView(std::unique_ptr<gi::Method> method, int maxSamplesPerPixel);
  ~ProgressiveView();  // cancels the batch in flight and joins the worker
  ProgressiveView(const ProgressiveView&) = delete;
  ProgressiveView& operator=(const ProgressiveView&) = delete;

  // The view to accumulate (width and height: the window's). A camera that differs from the last
  // in anything but its time restarts the accumulation and cancels the batch in flight.
  void setCamera(const gi::SceneCamera& camera);
  // Pixels per accumulated pixel along each axis: 0 picks it (the smallest power of two that
  // keeps one sample per pixel under a quarter of a second, as measured), else 1, 2, 4 or 8.
  void setDivisor(int divisor);
  // Paused (the window shows something else), the worker leaves the cores alone; resumed, it
  // starts the accumulation again.
  void setPaused(bool paused);

  struct Snapshot {
    gi::HdrImage mean;  // empty before the first batch completes
    int samplesPerPixel = 0;
    double seconds = 0;     // since the accumulation (re)started
    int divisor = 1;        // of the accumulation the mean comes from
    uint64_t version = 0;   // changes whenever the mean does
    bool complete = false;  // maxSamplesPerPixel reached
    std::string error;      // the method failed: what it said (accumulation stops)
  };
  // A copy of the latest mean (thread-safe).
  Snapshot snapshot() const;
  uint64_t version() const { return version_.load(); }
  // Blocks until the current camera's accumulation holds `samplesPerPixel` (or the most it will),
  // or `timeoutSeconds` pass; returns whether it got there. For scripted runs.
  bool waitFor(int samplesPerPixel, double timeoutSeconds) const;
  int maxSamplesPerPixel() const { return maxSpp_; }
  std::string methodName() const { return name_; }

 private:
  void run();
  int pickDivisor(const gi::SceneCamera& camera) const;

  std::unique_ptr<gi::Method> method_;
  const std::string name_;
  const int maxSpp_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  gi::SceneCamera camera_;
  bool hasCamera_ = false, paused_ = false;
  std::atomic<bool> stop_{false};
  int divisorSetting_ = 0;
  std::atomic<uint64_t> generation_{0};  // camera or divisor changes; a batch of an old one stops
  std::atomic<uint64_t> version_{0};
  Snapshot published_;
  uint64_t publishedGeneration_ = ~0ull;
  double secondsPerPixelSample_ = 0;  // measured; 0: nothing measured yet
  std::thread worker_;
};

}  // namespace nestlight::viewer
