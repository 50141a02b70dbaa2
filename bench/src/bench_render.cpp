// `nestlight bench render`: points per second of each rasteriser on this machine's GL (an NVIDIA
// GPU through EGL, or llvmpipe on the CPU), with the whole view's cut resident.
#include "nestlight/bench/bench_render.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/frame/point_view.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::bench {

namespace fs = std::filesystem;

namespace {

struct Path {
  const char* name;
  frame::Rasteriser rasteriser;
  frame::Splatting splatting;
  bool atomic64;  // compute: the one-pass 64-bit atomic rasteriser (else two 32-bit passes)
};
// The compute rasteriser both ways: two 32-bit passes everywhere, and one 64-bit pass
// (Schütz et al. 2021's) where the driver has 64-bit atomics; llvmpipe has not.
const Path kPaths[] = {{"points", frame::Rasteriser::Points, frame::Splatting::Basic, false},
                       {"points_hqs", frame::Rasteriser::Points, frame::Splatting::Hqs, false},
                       {"compute32", frame::Rasteriser::Compute, frame::Splatting::Basic, false},
                       {"compute64", frame::Rasteriser::Compute, frame::Splatting::Basic, true}};

// What every path draws: the view's whole cut, resident.
struct ResidentCut {
  const streaming::Streamer& streamer;
  const frame::GlNodeStore& store;
  const frame::Camera& camera;
  int width, height, runs;
};

// Budgets that hold every point of the scan resident (no spacing limit).
streaming::Budgets wholeCutBudgets() {
  streaming::Budgets budgets;
  budgets.points = 100'000'000;
  budgets.gpuBytes = 8ull << 30;
  budgets.uploadBytesPerFrame = 1ull << 30;
  budgets.spacingPixels = 0;  // every point of the scan: a rasteriser benchmark, not a LOD one
  return budgets;
}
// Streams in the whole cut of `view`; throws nestlight::Error after 10 minutes.
void loadWholeCut(streaming::Streamer& streamer, const streaming::View& view) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!streamer.update(view).complete) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > 600)
      throw Error("bench render: the cut did not load within 10 minutes");
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// One path's timed frames (the first, which allocates the targets, untimed): its table row and
// its entry in out["paths"]. basicMs: the basic GL_POINTS path's median, which HQS is put against.
void measurePath(const Path& path, frame::PointView& renderer, const ResidentCut& cut,
                 double& basicMs, nlohmann::json& out) {
  if (path.atomic64 && std::string(renderer.computeVariant()) != "one-pass 64-bit") {
    std::printf("%-12s %12s %14s  %s\n", path.name, "-", "-", "no 64-bit atomics on this driver");
    out["paths"][path.name] = {{"skipped", "no 64-bit atomics on this driver"}};
    return;
  }
  const auto& st = cut.streamer.stats();
  frame::RenderSettings s;
  s.rasteriser = path.rasteriser;
  s.splatting = path.splatting;
  s.allowAtomic64 = path.atomic64;
  if (path.rasteriser == frame::Rasteriser::Compute) s.fixedPointSize = 1;
  s.edlStrength = 0;  // the rasteriser alone
  std::vector<double> ms;
  for (int k = 0; k <= cut.runs; ++k) {
    frame::DrawTimings t;
    renderer.renderToTexture(cut.streamer.drawList(), cut.store, cut.camera, cut.width, cut.height,
                             s, &t);
    if (k > 0) ms.push_back(t.msDraw);  // the first frame allocates targets
  }
  std::sort(ms.begin(), ms.end());
  const double med = ms[ms.size() / 2];
  const double pps = st.drawPoints / (med / 1000.0);
  const bool compute = path.rasteriser == frame::Rasteriser::Compute;
  if (path.splatting == frame::Splatting::Basic && !compute) basicMs = med;
  const std::string variant =
      !compute        ? std::string("GL_POINTS, ") + frame::splattingName(path.splatting)
      : path.atomic64 ? "one-pass 64-bit"
                      : "two-pass 32-bit";
  std::string note = compute ? variant : "";
  if (path.splatting == frame::Splatting::Hqs && basicMs > 0) {
    char ratio[64];
    std::snprintf(ratio, sizeof ratio, "%.2fx basic", med / basicMs);
    note = ratio;
  }
  std::printf("%-12s %12.2f %14s  %s\n", path.name, med, humanCount(pps).c_str(), note.c_str());
  out["paths"][path.name] = {{"median_ms", med},
                             {"points_per_second", pps},
                             {"ms", ms},
                             {"points", st.drawPoints},
                             {"variant", variant}};
}

}  // namespace

void runBenchRender(const BenchRenderOptions& o) {
  const fs::path oct =
      o.octree.empty() ? ensureSyntheticOctree(
                             o.generate, fs::path(o.dir) / ("render_" + o.generateName + ".octree"))
                       : fs::path(o.octree);
  OctreeReader reader(oct);
  const Metadata& meta = reader.metadata();
  auto ctx = gl::createHeadlessContext();
  nlohmann::json out = {{"device", ctx->description()},
                        {"octree", oct.string()},
                        {"width", o.width},
                        {"height", o.height},
                        {"runs", o.runs}};
  {
    frame::GlNodeStore store(
        meta, meta.layout.has(attr::kRgb) ? frame::ColourMode::Rgb : frame::ColourMode::Elevation);
    frame::PointView renderer;
    streaming::Streamer streamer(reader, store, wholeCutBudgets());
    const frame::Camera cam = frame::Camera::framing(meta.bounds, 60, double(o.width) / o.height);
    loadWholeCut(streamer, cam.view(o.width, o.height));
    const auto& st = streamer.stats();
    std::printf("device  %s\nframe   %dx%d, %llu points in %u nodes resident\n\n",
                ctx->description().c_str(), o.width, o.height, (unsigned long long)st.drawPoints,
                st.drawNodes);
    std::printf("%-12s %12s %14s\n", "path", "median ms", "points/s");
    const ResidentCut cut{streamer, store, cam, o.width, o.height, o.runs};
    double basicMs = 0;
    for (const Path& path : kPaths) measurePath(path, renderer, cut, basicMs, out);
  }
  std::ofstream(o.out) << out.dump(1) << "\n";
  std::printf("\nresults written to %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
