// `nestlight generate` (seeded synthetic scans) and `nestlight demo`.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "cli.h"
#include "nestlight/converters/builder.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/converters/verify.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/render_scene.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/headless.h"
#include "nestlight/viewer/window_app.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void printBuildSummary(const BuildReport& r, const fs::path& out);

namespace {
Vec3d parseVec(const std::string& s) {
  Vec3d v;
  if (std::sscanf(s.c_str(), "%lf,%lf,%lf", &v.x, &v.y, &v.z) != 3)
    throw Error("", "", "expected x,y,z but got '" + s + "'");
  return v;
}
}  // namespace

void addGenerate(CLI::App& app, int& exitCode) {
  auto* cmd =
      app.add_subcommand("generate", "Write a seeded synthetic scan (tests, benchmarks, demos)");
  auto out = std::make_shared<std::string>();
  auto shape = std::make_shared<std::string>("surfaces");
  auto points = std::make_shared<std::string>("1000000");
  auto origin = std::make_shared<std::string>("0,0,0");
  auto spec = std::make_shared<SyntheticSpec>();
  cmd->add_option("-o,--output", *out, "Output file (.las, .laz or .ply)")->required();
  cmd->add_option("--shape", *shape,
                  "surfaces (a building-like scene), cube (filled volume), duplicates (one point "
                  "repeated), plane (zero extent in z)")
      ->check(CLI::IsMember({"surfaces", "cube", "duplicates", "plane"}))
      ->capture_default_str();
  cmd->add_option("-n,--points", *points, "Number of points (accepts 20M, 1.5G)")
      ->capture_default_str();
  cmd->add_option("--seed", spec->seed, "Random seed")->capture_default_str();
  cmd->add_option("--origin", *origin,
                  "Offset added to every point, x,y,z (national grid: 500000,5000000,100)")
      ->capture_default_str();
  cmd->add_option("--size", spec->size, "Extent in metres")->capture_default_str();
  cmd->add_option("--precision", spec->precision, "Coordinate quantum in metres")
      ->capture_default_str();
  cmd->add_flag("--normals", spec->normals, "Include analytic normals");
  cmd->callback([=, &exitCode]() {
    SyntheticSpec s = *spec;
    s.shape = *parseSyntheticShape(*shape);
    s.points = parseCount(*points, "--points");
    s.origin = parseVec(*origin);
    auto t = std::chrono::steady_clock::now();
    uint64_t n = writeSynthetic(s, *out);
    double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    std::printf("wrote %llu points (%s) to %s in %.2f s\n", (unsigned long long)n,
                *shape == "" ? "?" : shape->c_str(), out->c_str(), secs);
    exitCode = 0;
  });
}

void addDemo(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "demo",
      "Generate a synthetic scan, convert it, verify it, render it headless and say what was "
      "built\n"
      "and how fast; then light a generated room scan with an inserted sphere by path tracing "
      "and in\n"
      "real time through the GI frame (direct light; GI with VPLs beside the path tracer's image "
      "of the\n"
      "albedo mode); opens the viewer when a display is present. Exits 2 when the verify fails");
  auto pointsText = std::make_shared<std::string>("3M");
  auto dir = std::make_shared<std::string>();
  auto keep = std::make_shared<bool>(false);
  cmd->add_option("-n,--points", *pointsText, "Points in the synthetic scan (e.g. 200k, 3M)")
      ->capture_default_str();
  cmd->add_option("--dir", *dir, "Work folder (default: a temporary folder, removed afterwards)");
  cmd->add_flag("--keep", *keep, "Keep the work folder");
  auto image = std::make_shared<std::string>("nestlight-demo.png");
  auto noView = std::make_shared<bool>(false);
  cmd->add_option("--image", *image, "Where the headless render of the scan goes (.png or .exr)")
      ->capture_default_str();
  cmd->add_flag("--no-view", *noView, "Do not open the viewer even when a display is present");
  cmd->callback([=, &exitCode]() {
    fs::path work =
        dir->empty() ? fs::temp_directory_path() / ("nestlight-demo-" + std::to_string(::getpid()))
                     : fs::path(*dir);
    fs::create_directories(work);
    const uint64_t points = parseCount(*pointsText, "--points");
    SyntheticSpec spec;
    spec.points = points;
    spec.seed = 2026;
    const std::string las = (work / "demo_scan.las").string();
    std::printf("nestlight demo: a synthetic scanned scene of %s points\n",
                humanCount(double(points)).c_str());
    auto t = std::chrono::steady_clock::now();
    writeSynthetic(spec, las);
    std::printf("  generated %s (%s) in %.2f s\n", las.c_str(),
                humanBytes(double(fs::file_size(las))).c_str(),
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
    BuildOptions o;
    o.output = work / "demo.octree";
    o.overwrite = true;
    o.progress = ProgressMode::Quiet;
    std::vector<std::unique_ptr<PointReader>> readers;
    readers.push_back(openReader(las));
    BuildReport r = buildOctree(std::move(readers), o);
    printBuildSummary(r, o.output);
    t = std::chrono::steady_clock::now();
    OctreeReader reader(o.output);
    PointBuffer root = reader.readNode(NodeKey::root());
    double openMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    std::printf("  open      root node (%zu points) read in %.2f ms, %llu bytes of hierarchy\n",
                root.size(), openMs, (unsigned long long)reader.hierarchyBytesRead());
    VerifyReport v = verifyOctree(o.output);
    std::printf("  verify    %s (%llu nodes, %llu points)\n", v.ok() ? "OK" : "FAILED",
                (unsigned long long)v.nodes, (unsigned long long)v.points);
    for (auto& f : v.failures) std::printf("            %s\n", f.c_str());
    if (v.ok()) {
      viewer::RenderJob job;
      job.octree = o.output;
      job.output = *image;
      job.waitComplete = true;
      job.quiet = true;
      t = std::chrono::steady_clock::now();
      auto frames = viewer::renderHeadless(job);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
      std::printf("  render    %s: %dx%d, %s points in %u nodes, %.0f ms (streaming and drawing)\n",
                  image->c_str(), job.width, job.height,
                  humanCount(double(frames.at(0).stats.drawPoints)).c_str(),
                  frames.at(0).stats.drawNodes, ms);
      // Lighting: the Cornell-like test scene, path traced (a few seconds on two cores).
      TestSceneOptions so;
      so.points = 300'000;
      so.width = 200;
      so.height = 150;
      so.quiet = true;
      const fs::path scene = makeTestScene(TestSceneKind::Cornell, work / "cornell", so);
      gi::SceneRenderOverrides ov;
      ov.spp = 64;
      ov.quiet = true;
      ov.output = fs::path(*image).replace_extension("").string() + "-gi.exr";
      gi::SceneRenderReport gi = gi::renderSceneFile(scene, ov);
      std::printf(
          "  light     %s (+ .png): a scanned room lighting a glossy sphere, path traced (Embree), "
          "%d samples/pixel,\n"
          "            %.2f s, %.2f M rays/s, estimated error %.1f%%\n",
          gi.exr.c_str(), gi.result.samplesPerPixel, gi.result.seconds,
          gi.result.raysPerSecond() / 1e6, 100 * gi.result.relativeError);
      // The same room in real time through the GI frame: direct light with shadow maps (GL).
      gi::SceneRenderOverrides rov;
      rov.method = "raster";
      rov.quiet = true;
      rov.output = fs::path(*image).replace_extension("").string() + "-raster.exr";
      gi::SceneRenderReport ras = gi::renderSceneFile(scene, rov);
      std::string passes;
      for (const auto& [name, ms] : ras.result.passMs) {
        char p[64];
        std::snprintf(p, sizeof p, "%s%s %.1f ms", passes.empty() ? "" : ", ", name.c_str(), ms);
        passes += p;
      }
      std::printf(
          "  real time %s (+ .png): the same room through the GI frame (G-buffer, shadow maps, "
          "direct\n"
          "            light), %.0f ms per frame; GPU: %s\n",
          ras.exr.c_str(), ras.result.seconds * 1e3, passes.c_str());
      // Global illumination in real time: the room with the scan's colour as its reflectance
      // (albedo mode), lit by importance-warped VPLs with imperfect shadow maps, beside the path
      // tracer's image of the same mode.
      gi::SceneRenderOverrides vov;
      vov.method = "vpl";
      vov.mode = gi::RadianceMode::Albedo;
      vov.quiet = true;
      vov.output = fs::path(*image).replace_extension("").string() + "-vpl.exr";
      gi::SceneRenderReport vpl = gi::renderSceneFile(scene, vov);
      gi::SceneRenderOverrides aov;
      aov.mode = gi::RadianceMode::Albedo;
      aov.spp = 64;
      aov.quiet = true;
      aov.output = fs::path(*image).replace_extension("").string() + "-gi-albedo.exr";
      gi::SceneRenderReport albedoRef = gi::renderSceneFile(scene, aov);
      std::printf(
          "  real-time GI %s (+ .png): the room lit by %s VPLs with imperfect shadow maps (%s "
          "bounces),\n"
          "            %.0f ms per frame; the path tracer's %s (64 spp, %.1f s) differs by %.1f%% "
          "(relative L2,\n"
          "            its own noise included)\n",
          vpl.exr.c_str(), vpl.result.attributes["nestlight:vpls"].c_str(),
          std::to_string(vpl.scene.gi.maxBounces).c_str(), vpl.result.seconds * 1e3,
          albedoRef.exr.c_str(), albedoRef.result.seconds,
          100 * gi::relativeL2(vpl.result.image, albedoRef.result.image));
      const char* display = std::getenv("DISPLAY");
      const char* wayland = std::getenv("WAYLAND_DISPLAY");
      if (!*noView && ((display && *display) || (wayland && *wayland))) {
        std::printf("  view      opening the viewer (close the window to finish)\n");
        viewer::ViewerOptions vo;
        vo.octree = o.output;
        viewer::runViewer(vo);
      }
    }
    if (!*keep && dir->empty())
      fs::remove_all(work);
    else
      std::printf("  kept      %s\n", work.string().c_str());
    exitCode = v.ok() ? kExitOk : kExitCheckFailed;
  });
}

}  // namespace nestlight::cli
