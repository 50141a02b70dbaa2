// `nestlight bench frame`: the GI frame's cost per pass (GPU time of each pass, median of runs) for
// a scene and a real-time method at a given size: what every method built on the frame pays before
// its own work (G-buffer, shadow maps, tone map).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void addBenchFrame(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand("frame",
                                    "GPU time per pass of a real-time GI method's frame (median of "
                                    "--runs), interactive (tone-mapped, no\n"
                                    "read-back) and as a still (linear, read back). Without a "
                                    "scene, the generated cornell scene.\n"
                                    "Example: nestlight bench frame --width 1280 --height 720");
  auto scene = std::make_shared<std::string>();
  auto method = std::make_shared<std::string>("raster");
  auto dir = std::make_shared<std::string>("bench-data");
  auto points = std::make_shared<std::string>("1M");
  auto width = std::make_shared<int>(1280), height = std::make_shared<int>(720),
       runs = std::make_shared<int>(5);
  auto json = std::make_shared<std::string>("bench-frame.json");
  auto mode = std::make_shared<std::string>("albedo");
  cmd->add_option("scene", *scene, "Scene file (default: make-scene cornell in --dir)");
  cmd->add_option("--method", *method, "A real-time method (" + gi::methodList() + ")")
      ->capture_default_str();
  cmd->add_option("--mode", *mode, "radiance_cache or albedo")
      ->check(CLI::IsMember({"radiance_cache", "albedo"}))
      ->capture_default_str();
  cmd->add_option("--points", *points, "Points of the generated scene's scan")
      ->capture_default_str();
  cmd->add_option("--dir", *dir, "Folder for the generated scene (reused)")->capture_default_str();
  cmd->add_option("--width", *width, "Frame width")
      ->capture_default_str()
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--height", *height, "Frame height")
      ->capture_default_str()
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--runs", *runs, "Timed frames (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--json", *json, "Where to write the results")->capture_default_str();
  auto params = std::make_shared<std::vector<std::string>>();
  cmd->add_option(
      "--param", *params,
      "A method parameter as the scene's gi.parameters takes it, KEY=VALUE (VALUE as JSON, else a "
      "string),\n"
      "e.g. --param vpls=1024 --param variant=classic --param estimator=smc; repeatable");
  cmd->callback([=, &exitCode]() {
    const gi::MethodInfo* info = gi::findMethod(*method);
    if (!info) throw Error("--method: unknown method '" + *method + "' (" + gi::methodList() + ")");
    if (!info->gpu) throw Error("--method: " + *method + " is not a real-time (GL) method");
    fs::path file = *scene;
    if (file.empty()) {
      TestSceneOptions so;
      so.points = parseCount(*points, "--points");
      so.quiet = true;
      file =
          makeTestScene(TestSceneKind::Cornell, fs::path(*dir) / ("frame_cornell_" + *points), so);
    }
    gi::Scene s = gi::loadScene(file);
    s.gi.method = *method;
    s.gi.mode = *mode == "albedo" ? gi::RadianceMode::Albedo : gi::RadianceMode::RadianceCache;
    for (const std::string& p : *params) {
      const size_t eq = p.find('=');
      if (eq == std::string::npos || eq == 0) throw Error("--param: '" + p + "' is not KEY=VALUE");
      const std::string value = p.substr(eq + 1);
      nlohmann::json v = nlohmann::json::parse(value, nullptr, false);
      s.gi.parameters[p.substr(0, eq)] = v.is_discarded() ? nlohmann::json(value) : v;
    }
    s.camera.width = *width;
    s.camera.height = *height;
    auto ctx = gl::createHeadlessContext();
    nlohmann::json out = {{"device", ctx->description()},
                          {"scene", fs::absolute(file).string()},
                          {"method", *method},
                          {"width", *width},
                          {"height", *height},
                          {"runs", *runs}};
    std::printf("device  %s\nscene   %s, %s, %dx%d\n", ctx->description().c_str(), file.c_str(),
                method->c_str(), *width, *height);
    {
      std::unique_ptr<gi::Method> m = gi::createMethod(s, {true, true});
      for (const auto& [k, v] : m->parameters()) out["parameters"][k] = v;
      // Interactive frames first: the first one streams the cut in completely (a still), so every
      // timed frame draws the same points.
      gi::MethodFrame still = m->render(s.camera);
      for (const bool interactive : {true, false}) {
        std::map<std::string, std::vector<double>> pass;
        std::vector<std::string> order;
        std::vector<double> frameMs;
        for (int r = 0; r <= *runs; ++r) {
          gi::MethodFrame f;
          if (interactive)
            m->renderInteractive(s.camera, 0.0f, &f);
          else
            f = m->render(s.camera);
          if (r == 0) continue;  // the first frame compiles the graph for its output, allocates
          frameMs.push_back(f.seconds * 1e3);
          for (const auto& [name, ms] : f.passMs) {
            if (!pass.count(name)) order.push_back(name);
            pass[name].push_back(ms);
          }
        }
        const char* label = interactive ? "interactive" : "still";
        std::printf("\n%s (%s)\n%-16s %10s\n", label,
                    interactive ? "tone-mapped into the window's texture" : "linear, read back",
                    "pass", "median ms");
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
      out["summary"] = still.summary;
    }
    std::ofstream(*json) << out.dump(1) << "\n";
    std::printf("\nresults written to %s\n", json->c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
