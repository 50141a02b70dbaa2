#include "nestlight/viewer/progressive.h"

#include <algorithm>
#include <chrono>
#include <vector>

#include "nestlight/octree/error.h"

namespace nestlight::viewer {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The camera's view without its time: a video light probe playing on must not restart the
// accumulation every frame.
bool sameView(const gi::SceneCamera& a, const gi::SceneCamera& b) {
  return a.eye == b.eye && a.target == b.target && a.up == b.up && a.fovYDegrees == b.fovYDegrees &&
         a.width == b.width && a.height == b.height;
}

// A batch should take about this long: short enough that a camera move is answered within it
// (the batch also stops after each sample per pixel once cancelled), long enough that the
// window's uploads of the mean do not outweigh the sampling.
constexpr double kBatchSeconds = 0.25;

}  // namespace

ProgressiveView::ProgressiveView(std::unique_ptr<gi::Method> method, int maxSamplesPerPixel)
    : method_(std::move(method)), name_(method_->name()), maxSpp_(std::max(maxSamplesPerPixel, 1)) {
  NL_CHECK_MSG(method_->rendersInBatches(), name_ + " does not render in batches");
  worker_ = std::thread([this] { run(); });
}

ProgressiveView::~ProgressiveView() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void ProgressiveView::setCamera(const gi::SceneCamera& camera) {
  {
    std::lock_guard lock(mutex_);
    if (hasCamera_ && sameView(camera, camera_)) return;
    camera_ = camera;
    hasCamera_ = true;
    ++generation_;
  }
  changed_.notify_all();
}

void ProgressiveView::setDivisor(int divisor) {
  {
    std::lock_guard lock(mutex_);
    if (divisor == divisorSetting_) return;
    divisorSetting_ = divisor;
    ++generation_;
  }
  changed_.notify_all();
}

void ProgressiveView::setPaused(bool paused) {
  {
    std::lock_guard lock(mutex_);
    if (paused == paused_) return;
    paused_ = paused;
    ++generation_;  // the batch in flight stops
  }
  changed_.notify_all();
}

ProgressiveView::Snapshot ProgressiveView::snapshot() const {
  std::lock_guard lock(mutex_);
  return published_;
}

bool ProgressiveView::waitFor(int samplesPerPixel, double timeoutSeconds) const {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, std::chrono::duration<double>(timeoutSeconds), [&] {
    return !published_.error.empty() ||
           (publishedGeneration_ == generation_.load() &&
            (published_.samplesPerPixel >= samplesPerPixel || published_.complete));
  });
}

int ProgressiveView::pickDivisor(const gi::SceneCamera& c) const {
  if (divisorSetting_ > 0) return divisorSetting_;
  const double pixels = double(c.width) * c.height;
  int d = 1;
  // Before anything is measured, a first pass of at most 320 x 240 pixels answers quickly.
  if (secondsPerPixelSample_ > 0)
    while (d < 8 && secondsPerPixelSample_ * pixels / (d * d) > kBatchSeconds) d *= 2;
  else
    while (d < 8 && pixels / (d * d) > 320.0 * 240.0) d *= 2;
  return d;
}

void ProgressiveView::run() {
  std::unique_lock lock(mutex_);
  uint64_t accumulating = ~0ull, batch = 0;
  gi::SceneCamera cam;
  std::vector<double> sum;  // sums of samples: float would lose small ones after thousands
  int spp = 0, divisor = 1, holdUntil = 1;
  Clock::time_point start = Clock::now();
  bool failed = false;
  while (!stop_) {
    const uint64_t g = generation_.load();
    if (!hasCamera_ || paused_ || (failed && g == accumulating) ||
        (g == accumulating && spp >= maxSpp_)) {
      changed_.wait(lock,
                    [&] { return stop_ || (hasCamera_ && !paused_ && generation_.load() != g); });
      continue;
    }
    // A camera at rest at a reduced resolution: once the coarse mean holds 16 samples and a finer
    // sample per pixel would take at most a second, accumulate again at twice the resolution;
    // the coarse mean stays on screen until the finer one holds 4 samples.
    const bool refine =
        g == accumulating && divisorSetting_ == 0 && divisor > 1 && spp >= 16 &&
        secondsPerPixelSample_ * double(camera_.width) * camera_.height / (divisor * divisor / 4) <=
            4 * kBatchSeconds;
    if (g != accumulating || refine) {
      if (g != accumulating) start = Clock::now();
      accumulating = g, failed = false;
      divisor = refine ? divisor / 2 : pickDivisor(camera_);
      holdUntil = refine ? 4 : 1;
      cam = camera_;
      cam.width = std::max(1, (camera_.width + divisor - 1) / divisor);
      cam.height = std::max(1, (camera_.height + divisor - 1) / divisor);
      sum.assign(size_t(cam.width) * cam.height * 3, 0.0);
      spp = 0;
    }
    const double pixels = double(cam.width) * cam.height;
    int k = 1;
    if (secondsPerPixelSample_ > 0)
      k = std::clamp(int(kBatchSeconds / (secondsPerPixelSample_ * pixels)), 1, 16);
    k = std::min(k, maxSpp_ - spp);
    lock.unlock();
    const Clock::time_point t0 = Clock::now();
    gi::MethodFrame f;
    std::string error;
    try {
      f = method_->renderBatch(cam, k, batch++, [&] { return !stop_ && generation_.load() == g; });
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double seconds = secondsSince(t0);
    lock.lock();
    if (!error.empty()) {
      failed = true;
      published_.error = error;
      version_ = ++published_.version;
      changed_.notify_all();
      continue;
    }
    if (f.samplesPerPixel > 0) secondsPerPixelSample_ = seconds / (f.samplesPerPixel * pixels);
    if (stop_ || generation_.load() != g || f.samplesPerPixel <= 0) continue;  // stale: dropped
    const double n = f.samplesPerPixel;
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += double(f.image.rgb[i]) * n;
    spp += f.samplesPerPixel;
    if (spp < holdUntil) continue;
    published_.mean = gi::HdrImage(cam.width, cam.height);
    for (size_t i = 0; i < sum.size(); ++i) published_.mean.rgb[i] = float(sum[i] / spp);
    published_.samplesPerPixel = spp;
    published_.seconds = secondsSince(start);
    published_.divisor = divisor;
    published_.complete = spp >= maxSpp_;
    published_.error.clear();
    publishedGeneration_ = g;
    version_ = ++published_.version;
    changed_.notify_all();
  }
}

}  // namespace nestlight::viewer
