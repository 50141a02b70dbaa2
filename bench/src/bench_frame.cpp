// `nestlight bench frame`: the GI frame's cost per pass (GPU time of each pass, median of runs) for
// a scene and a real-time method at a given size: what every method built on the frame pays before
// its own work (G-buffer, shadow maps, tone map).
#include "nestlight/bench/bench_frame.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;

namespace {

// The scene file (made when none is given), with the options' method, mode, parameters and size.
gi::Scene frameScene(const BenchFrameOptions& o, fs::path& file) {
  const gi::MethodInfo* info = gi::findMethod(o.method);
  if (!info) throw Error("--method: unknown method '" + o.method + "' (" + gi::methodList() + ")");
  if (!info->gpu) throw Error("--method: " + o.method + " is not a real-time (GL) method");
  file = o.scene;
  if (file.empty()) {
    TestSceneOptions so;
    so.points = o.points;
    so.quiet = true;
    file = makeTestScene(TestSceneKind::Cornell,
                         fs::path(o.dir) / ("frame_cornell_" + o.pointsName), so);
  }
  gi::Scene s = gi::loadScene(file);
  gi::checkSceneMethod(s);  // as the file says, before --method replaces it
  s.gi.method = o.method;
  s.gi.mode = o.mode == "albedo" ? gi::RadianceMode::Albedo : gi::RadianceMode::RadianceCache;
  for (const std::string& p : o.params) {
    const size_t eq = p.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("--param: '" + p + "' is not KEY=VALUE");
    const std::string value = p.substr(eq + 1);
    nlohmann::json v = nlohmann::json::parse(value, nullptr, false);
    s.gi.parameters[p.substr(0, eq)] = v.is_discarded() ? nlohmann::json(value) : v;
  }
  s.camera.width = o.width;
  s.camera.height = o.height;
  return s;
}

// Interactive frames (tone-mapped into the window's texture) or stills (linear, read back): the
// median GPU time of each pass, their total and the frame's wall time, printed and in `out`.
void measureFrames(gi::Method& m, const gi::Scene& s, const BenchFrameOptions& o, bool interactive,
                   nlohmann::json& out) {
  std::map<std::string, std::vector<double>> pass;
  std::vector<std::string> order;
  std::vector<double> frameMs;
  for (int r = 0; r <= o.runs; ++r) {
    gi::MethodFrame f;
    if (interactive)
      m.renderInteractive(s.camera, 0.0f, &f);
    else
      f = m.render(s.camera);
    if (r == 0) continue;  // the first frame compiles the graph for its output, allocates
    frameMs.push_back(f.seconds * 1e3);
    for (const auto& [name, ms] : f.passMs) {
      if (!pass.count(name)) order.push_back(name);
      pass[name].push_back(ms);
    }
  }
  const char* label = interactive ? "interactive" : "still";
  std::printf("\n%s (%s)\n%-16s %10s\n", label,
              interactive ? "tone-mapped into the window's texture" : "linear, read back", "pass",
              "median ms");
  double total = 0;
  for (const auto& name : order) {
    const double med = median(pass[name]);
    total += med;
    std::printf("%-16s %10.3f\n", name.c_str(), med);
    out[label]["passes_ms"][name] = med;
  }
  const double wall = median(frameMs);
  std::printf("%-16s %10.3f\n%-16s %10.3f\n", "GPU total", total, "frame (wall)", wall);
  out[label]["gpu_total_ms"] = total;
  out[label]["frame_ms"] = wall;
  out[label]["frame_ms_runs"] = frameMs;
}

}  // namespace

void runBenchFrame(const BenchFrameOptions& o) {
  fs::path file;
  const gi::Scene s = frameScene(o, file);
  auto ctx = gl::createHeadlessContext();
  nlohmann::json out = {{"device", ctx->description()}, {"scene", fs::absolute(file).string()},
                        {"method", o.method},           {"width", o.width},
                        {"height", o.height},           {"runs", o.runs}};
  std::printf("device  %s\nscene   %s, %s, %dx%d\n", ctx->description().c_str(), file.c_str(),
              o.method.c_str(), o.width, o.height);
  {
    std::unique_ptr<gi::Method> m = gi::createMethod(s, {true, true});
    for (const auto& [k, v] : m->parameters()) out["parameters"][k] = v;
    // Interactive frames first: the first one streams the cut in completely (a still), so every
    // timed frame draws the same points.
    gi::MethodFrame still = m->render(s.camera);
    for (const bool interactive : {true, false}) measureFrames(*m, s, o, interactive, out);
    out["summary"] = still.summary;
  }
  std::ofstream(o.out) << out.dump(1) << "\n";
  std::printf("\nresults written to %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
