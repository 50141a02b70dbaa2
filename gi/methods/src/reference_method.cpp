// `reference` and `direct` as registered methods: the path tracer of gi/reference, all bounces or
// one (nestlight/gi/reference/path_tracer.h).
#include "reference_method.h"

#include <algorithm>
#include <cstdio>
#include <limits>

#include "nestlight/gi/environment_source.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/shared/reference_scene.h"

namespace nestlight::gi {

namespace {

// A path-traced image as a method's frame (its image moved out of `r`).
MethodFrame frameOf(ReferenceResult& r) {
  MethodFrame f;
  f.image = std::move(r.image);
  f.seconds = r.seconds;
  f.samplesPerPixel = r.samplesPerPixel;
  f.relativeError = r.relativeError;
  f.rays = r.rays;
  f.nonFiniteSamples = r.nonFiniteSamples;
  f.stopReason = r.stopReason;
  return f;
}

void logLine(const std::string& line) {
  std::fprintf(stderr, "  %s\n", line.c_str());
}

class ReferenceMethod : public Method {
 public:
  ReferenceMethod(const Scene& scene, const MethodContext& ctx, int maxBounces)
      : name_(scene.gi.method), quiet_(ctx.quiet), options_(referenceOptionsFrom(scene.gi)) {
    options_.maxBounces = std::min(options_.maxBounces, maxBounces);
    scene_ = ReferenceScene::load(scene, quiet_ ? nullptr : &logLine);
    // A video light probe: each camera's time picks the frame (the load lit the first).
    if (scene.environment && !scene.environment->sequence.empty())
      environment_ = std::make_unique<EnvironmentSource>(scene.environment);
  }
  std::string name() const override { return name_; }

  MethodFrame render(const SceneCamera& camera) override {
    int lastReported = 0;
    auto progress = [&](const ReferenceProgress& p) {
      if (!quiet_ && (p.samplesPerPixel >= 2 * lastReported ||
                      p.samplesPerPixel == options_.maxSamplesPerPixel)) {
        lastReported = p.samplesPerPixel;
        std::fprintf(stderr, "  %5d spp  %7.2f s  estimated error %.4f\n", p.samplesPerPixel,
                     p.seconds, p.relativeError);
      }
      return true;
    };
    size_t envFrame = 0;
    if (environment_) {
      envFrame = environment_->frameAt(camera.time);
      scene_->setEnvironment(environment_->at(camera.time));
    }
    ReferenceResult r = renderReference(*scene_, camera, options_, progress);
    MethodFrame f = frameOf(r);
    f.attributes = {{"nestlight:samples", std::to_string(r.samplesPerPixel)},
                    {"nestlight:relative_error_estimate", std::to_string(r.relativeError)},
                    {"nestlight:seconds", std::to_string(r.seconds)},
                    {"nestlight:rays", std::to_string(r.rays)},
                    {"nestlight:max_bounces", std::to_string(options_.maxBounces)},
                    {"nestlight:stop", r.stopReason}};
    if (environment_) f.attributes["nestlight:environment_frame"] = std::to_string(envFrame);
    char line[256];
    std::snprintf(line, sizeof line,
                  "%d samples/pixel in %.2f s (%s), estimated relative error %.4f, %.2f M rays/s, "
                  "%.0f k samples/s",
                  f.samplesPerPixel, f.seconds, f.stopReason.c_str(), f.relativeError,
                  f.raysPerSecond() / 1e6, f.samplesPerSecond() / 1e3);
    f.summary = line;
    if (f.nonFiniteSamples)
      f.summary += ", " + std::to_string(f.nonFiniteSamples) + " non-finite samples dropped";
    return f;
  }

  bool rendersInBatches() const override { return true; }

  // A batch is a render of `samples` passes with a seed of its own: the path tracer's samples of
  // pixel p in pass k hash (seed, p, k), so another seed gives independent samples (seeds that
  // differ by d collide only where d times the hash's odd constant lands within the image's pixel
  // count of 0 mod 2^64, which no batch count reaches).
  MethodFrame renderBatch(const SceneCamera& camera, int samples, uint64_t batch,
                          const std::function<bool()>& keepGoing) override {
    ReferenceOptions o = options_;
    o.maxSamplesPerPixel = std::max(samples, 1);
    o.targetRelativeError = 0;
    o.timeLimitSeconds = 0;
    o.seed = options_.seed + 1 + batch;
    if (environment_) scene_->setEnvironment(environment_->at(camera.time));
    ReferenceResult r = renderReference(
        *scene_, camera, o, [&](const ReferenceProgress&) { return !keepGoing || keepGoing(); });
    return frameOf(r);
  }

  uint64_t discs() const { return scene_->discs(); }

 private:
  std::string name_;
  bool quiet_;
  ReferenceOptions options_;
  std::unique_ptr<ReferenceScene> scene_;
  std::unique_ptr<EnvironmentSource> environment_;
};

}  // namespace

std::unique_ptr<Method> createReferenceMethod(const Scene& scene, const MethodContext& ctx) {
  return std::make_unique<ReferenceMethod>(scene, ctx, std::numeric_limits<int>::max());
}

std::unique_ptr<Method> createDirectMethod(const Scene& scene, const MethodContext& ctx) {
  return std::make_unique<ReferenceMethod>(scene, ctx, 1);
}

}  // namespace nestlight::gi
