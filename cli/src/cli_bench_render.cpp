// `nestlight bench render`: points per second of each rasteriser on this machine's GL (an NVIDIA
// GPU through EGL, or llvmpipe on the CPU), with the whole view's cut resident.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/frame_renderer.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void addBenchRender(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand("render",
                                    "Rasteriser speed (points/s): GL_POINTS with basic and with "
                                    "high-quality splatting, and the compute path");
  auto octree = std::make_shared<std::string>();
  auto generate = std::make_shared<std::string>("5M");
  auto dir = std::make_shared<std::string>("bench-data");
  auto width = std::make_shared<int>(1920), height = std::make_shared<int>(1080),
       runs = std::make_shared<int>(5);
  auto json = std::make_shared<std::string>("bench-render.json");
  cmd->add_option("octree", *octree, "Octree to render (default: a generated synthetic scan)");
  cmd->add_option("--generate", *generate, "Points of the synthetic scan when no octree is given")
      ->capture_default_str();
  cmd->add_option("--dir", *dir, "Folder for the generated scan (reused)")->capture_default_str();
  cmd->add_option("--width", *width, "Frame width")->capture_default_str();
  cmd->add_option("--height", *height, "Frame height")->capture_default_str();
  cmd->add_option("--runs", *runs, "Timed frames per rasteriser (the median is reported)")
      ->capture_default_str();
  cmd->add_option("--json", *json, "Where to write the results")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    const fs::path oct = octree->empty() ? ensureSyntheticOctree(
                                               parseCount(*generate, "--generate"),
                                               fs::path(*dir) / ("render_" + *generate + ".octree"))
                                         : fs::path(*octree);
    OctreeReader reader(oct);
    const Metadata& meta = reader.metadata();
    auto ctx = gl::createHeadlessContext();
    nlohmann::json out = {{"device", ctx->description()},
                          {"octree", oct.string()},
                          {"width", *width},
                          {"height", *height},
                          {"runs", *runs}};
    {
      frame::GlNodeStore store(meta, meta.layout.has(attr::kRgb) ? frame::ColourMode::Rgb
                                                                 : frame::ColourMode::Elevation);
      viewer::FrameRenderer renderer;
      streaming::Budgets budgets;
      budgets.points = 100'000'000;
      budgets.gpuBytes = 8ull << 30;
      budgets.uploadBytesPerFrame = 1ull << 30;
      budgets.spacingPixels = 0;  // every point of the scan: a rasteriser benchmark, not a LOD one
      streaming::Streamer streamer(reader, store, budgets);
      viewer::Camera cam = viewer::Camera::framing(meta.bounds, 60, double(*width) / *height);
      const streaming::View view = cam.view(*width, *height);
      const auto t0 = std::chrono::steady_clock::now();
      while (!streamer.update(view).complete) {
        if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > 600)
          throw Error("bench render: the cut did not load within 10 minutes");
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      const auto& st = streamer.stats();
      std::printf("device  %s\nframe   %dx%d, %llu points in %u nodes resident\n\n",
                  ctx->description().c_str(), *width, *height, (unsigned long long)st.drawPoints,
                  st.drawNodes);
      std::printf("%-12s %12s %14s\n", "path", "median ms", "points/s");
      struct Path {
        const char* name;
        viewer::Rasteriser rasteriser;
        viewer::Splatting splatting;
        bool atomic64;  // compute: the one-pass 64-bit atomic rasteriser (else two 32-bit passes)
      };
      // The compute rasteriser both ways: two 32-bit passes everywhere, and one 64-bit pass
      // (Schütz et al. 2021's) where the driver has 64-bit atomics; llvmpipe has not.
      const Path paths[] = {
          {"points", viewer::Rasteriser::Points, viewer::Splatting::Basic, false},
          {"points_hqs", viewer::Rasteriser::Points, viewer::Splatting::Hqs, false},
          {"compute32", viewer::Rasteriser::Compute, viewer::Splatting::Basic, false},
          {"compute64", viewer::Rasteriser::Compute, viewer::Splatting::Basic, true}};
      double basicMs = 0;
      for (const Path& path : paths) {
        if (path.atomic64 && std::string(renderer.computeVariant()) != "one-pass 64-bit") {
          std::printf("%-12s %12s %14s  %s\n", path.name, "-", "-",
                      "no 64-bit atomics on this driver");
          out["paths"][path.name] = {{"skipped", "no 64-bit atomics on this driver"}};
          continue;
        }
        viewer::RenderSettings s;
        s.rasteriser = path.rasteriser;
        s.splatting = path.splatting;
        s.allowAtomic64 = path.atomic64;
        if (path.rasteriser == viewer::Rasteriser::Compute) s.fixedPointSize = 1;
        s.edlStrength = 0;  // the rasteriser alone
        std::vector<double> ms;
        for (int k = 0; k <= *runs; ++k) {
          viewer::DrawTimings t;
          renderer.renderToTexture(streamer.drawList(), store, cam, *width, *height, s, &t);
          if (k > 0) ms.push_back(t.msDraw);  // the first frame allocates targets
        }
        std::sort(ms.begin(), ms.end());
        const double med = ms[ms.size() / 2];
        const double pps = st.drawPoints / (med / 1000.0);
        const bool compute = path.rasteriser == viewer::Rasteriser::Compute;
        if (path.splatting == viewer::Splatting::Basic && !compute) basicMs = med;
        const std::string variant =
            !compute        ? std::string("GL_POINTS, ") + viewer::splattingName(path.splatting)
            : path.atomic64 ? "one-pass 64-bit"
                            : "two-pass 32-bit";
        std::string note = compute ? variant : "";
        if (path.splatting == viewer::Splatting::Hqs && basicMs > 0) {
          char ratio[64];
          std::snprintf(ratio, sizeof ratio, "%.2fx basic", med / basicMs);
          note = ratio;
        }
        std::printf("%-12s %12.2f %14s  %s\n", path.name, med, humanCount(pps).c_str(),
                    note.c_str());
        out["paths"][path.name] = {{"median_ms", med},
                                   {"points_per_second", pps},
                                   {"ms", ms},
                                   {"points", st.drawPoints},
                                   {"variant", variant}};
      }
    }
    std::ofstream(*json) << out.dump(1) << "\n";
    std::printf("\nresults written to %s\n", json->c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
