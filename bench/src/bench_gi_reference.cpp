// The cached path-traced reference of `bench gi` and `bench diffrender` (bench_gi_reference.h).
#include "bench_gi_reference.h"

#include <algorithm>
#include <fstream>
#include <functional>

#include "bench_gi_differential.h"
#include "nestlight/bench/harness.h"
#include "nestlight/gi/environment_sequence.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/reference/path_tracer.h"  // kReferenceModelVersion, by reference_scene.h
#include "nestlight/octree/error.h"

namespace nestlight::bench::reference {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string fileHash(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return std::to_string(std::hash<std::string>{}(bytes));
}

// What the reference depends on besides the scene file: its octrees (metadata and payload),
// meshes and environment map, by size and modification time, so an edited asset is noticed.
std::string assetStamp(const gi::Scene& s) {
  std::string stamp;
  auto add = [&](const fs::path& p) {
    std::error_code ec;
    auto size = fs::file_size(p, ec);
    auto time = fs::last_write_time(p, ec).time_since_epoch().count();
    stamp += p.string() + "=" + std::to_string(ec ? 0 : size) + "@" +
             std::to_string(ec ? 0 : time) + ";";
  };
  for (const auto& o : s.octrees) {
    add(o.path / "metadata.json");
    add(o.path / "octree.bin");
  }
  for (const auto& m : s.meshes) add(m.path);
  if (s.environment && !s.environment->path.empty()) add(s.environment->path);
  if (s.environment && !s.environment->sequence.empty()) {
    try {
      const gi::EnvironmentSequence seq(gi::sequenceSpec(*s.environment));
      for (size_t i = 0; i < seq.frames(); ++i) add(seq.framePath(i));
    } catch (const Error&) {
      add(s.environment->sequence);  // the render names what is wrong with it
    }
  }
  return std::to_string(std::hash<std::string>{}(stamp));
}

}  // namespace

gi::Scene sceneFor(const gi::Scene& probe, const std::string& method, const std::string& mode,
                   int width, int height) {
  gi::Scene s = probe;
  if (const gi::MethodInfo* m = gi::findMethod(method);
      m && method != probe.gi.method && s.gi.parameters.is_object()) {
    const std::vector<std::string> known = gi::parameterNames(m->parameters);
    for (auto it = s.gi.parameters.begin(); it != s.gi.parameters.end();)
      it = std::find(known.begin(), known.end(), it.key()) == known.end()
               ? s.gi.parameters.erase(it)
               : std::next(it);
  }
  s.gi.method = method;
  if (mode == "albedo") s.gi.mode = gi::RadianceMode::Albedo;
  if (mode == "radiance_cache") s.gi.mode = gi::RadianceMode::RadianceCache;
  s.camera.width = width;
  s.camera.height = height;
  return s;
}

Image loadOrRender(const Request& o, const fs::path& path, std::FILE* log, bool withoutInserted) {
  const std::string key =
      "model" + std::to_string(gi::kReferenceModelVersion) + ":" + fileHash(o.sceneFile) + ":" +
      assetStamp(o.probe) + ":" + std::to_string(o.width) + "x" + std::to_string(o.height) + ":" +
      std::to_string(o.error) + ":" + o.mode + (withoutInserted ? ":without-inserted" : "");
  Image ref;
  if (!o.force && fs::exists(path)) {
    gi::ImageAttributes attrs;
    gi::HdrImage img = gi::readHdrImage(path.string(), &attrs);
    if (attrs["nestlight:cache_key"] == key) {
      ref.image = std::move(img);
      ref.info = {{"cached", true},
                  {"samples", attrs["nestlight:samples"]},
                  {"relative_error_estimate", attrs["nestlight:relative_error_estimate"]},
                  {"seconds", attrs["nestlight:seconds"]}};
      return ref;
    }
  }
  say(log, "%s: rendering the reference%s to %.4g relative error (at most %.0f s, %d spp)...\n",
      o.who.c_str(), withoutInserted ? " without the inserted meshes (R0)" : "", o.error,
      o.timeLimit, o.spp);
  gi::Scene s = sceneFor(o.probe, "reference", o.mode, o.width, o.height);
  if (withoutInserted) s = differential::withoutInserted(std::move(s));
  s.gi.targetRelativeError = o.error;
  s.gi.timeLimitSeconds = o.timeLimit;
  s.gi.samplesPerPixel = o.spp;
  s.gi.seed = 0x5eed;  // independent of the measured runs' seed
  gi::MethodFrame r = gi::createMethod(s, {true, false})->render(s.camera);
  ref.image = r.image;
  // One that stopped short of the error target (time or sample limit) is kept for this run
  // but not reused: the next run tries again.
  gi::ImageAttributes attrs{
      {"nestlight:cache_key", r.stopReason == "error target" ? key : "incomplete"},
      {"nestlight:samples", std::to_string(r.samplesPerPixel)},
      {"nestlight:relative_error_estimate", std::to_string(r.relativeError)},
      {"nestlight:seconds", std::to_string(r.seconds)},
      {"nestlight:stop", r.stopReason}};
  gi::writeExr(path.string(), ref.image, attrs);
  ref.info = {{"cached", false},
              {"samples", r.samplesPerPixel},
              {"relative_error_estimate", r.relativeError},
              {"seconds", r.seconds},
              {"stop", r.stopReason},
              {"rays_per_second", r.raysPerSecond()},
              {"samples_per_second", r.samplesPerSecond()}};
  say(log, "  reference: %d spp, estimated error %.4f, %.1f s (%s)\n", r.samplesPerPixel,
      r.relativeError, r.seconds, r.stopReason.c_str());
  if (r.stopReason != "error target")
    say(log,
        "  warning: the reference stopped before %.4g error; errors below its own are not "
        "meaningful\n",
        o.error);
  return ref;
}

}  // namespace nestlight::bench::reference
