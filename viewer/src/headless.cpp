#include "nestlight/viewer/headless.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/gl/context.h"
#include "nestlight/octree/crs.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/annotations.h"
#include "nestlight/viewer/image.h"

namespace nestlight::viewer {

namespace fs = std::filesystem;

namespace {

std::string frameFile(const std::string& pattern, int frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%04d", frame);
  const auto at = pattern.find("%04d");
  if (at != std::string::npos) return pattern.substr(0, at) + buf + pattern.substr(at + 4);
  const fs::path p(pattern);
  return (p.parent_path() / (p.stem().string() + "_" + buf + p.extension().string())).string();
}

}  // namespace

std::vector<RenderedFrame> renderHeadless(const RenderJob& job) {
  OctreeReader reader(job.octree);  // before any GL work: a bad octree fails here
  const Metadata& meta = reader.metadata();
  const frame::ColourMode mode =
      job.colour
          ? *job.colour
          : (meta.layout.has(attr::kRgb) ? frame::ColourMode::Rgb : frame::ColourMode::Elevation);
  const auto modes = frame::availableColourModes(meta, job.colourLayer);
  if (mode == frame::ColourMode::Hdr && !meta.layer(job.colourLayer))
    throw Error(
        job.octree.string(), "",
        "the scan has no colour layer '" + job.colourLayer + "' (nestlight expand-hdr makes one)");
  if (std::find(modes.begin(), modes.end(), mode) == modes.end())
    throw Error(job.octree.string(), "",
                std::string("the scan has no attribute for colour mode '") +
                    frame::colourModeName(mode) + "'");
  // An HDR layer is drawn in linear colour: EXR files keep it whole, PNG files clamp it.
  std::shared_ptr<const ColourLayerReader> layer;
  frame::RenderSettings settings = job.settings;
  if (mode == frame::ColourMode::Hdr) {
    layer = std::make_shared<const ColourLayerReader>(job.octree, meta, job.colourLayer);
    settings.linearOutput = true;
  }
  const std::string unit = describeCrs(meta.crs).unitSymbol();  // measurements' labels
  auto context = gl::createHeadlessContext();
  if (!job.quiet) std::printf("render: %s\n", context->description().c_str());
  {
    frame::GlNodeStore store(meta, mode, layer);
    frame::PointView renderer;
    std::vector<RenderedFrame> out;
    {
      streaming::Streamer streamer(reader, store, job.budgets);
      std::ofstream csv;
      if (!job.statsCsv.empty()) {
        csv.open(job.statsCsv);
        if (!csv) throw Error(job.statsCsv, "", "cannot write stats CSV");
        csv << "frame,file,complete,cut_nodes,cut_points,draw_nodes,draw_points,resident_nodes,"
               "resident_bytes,"
               "uploads,upload_bytes,evictions,cancelled,queue,in_flight,bytes_read,bad_nodes,ms_"
               "cut,ms_upload,"
               "ms_update,ms_draw\n";
      }
      const int frames = job.path ? job.path->frames() : 1;
      for (int f = 0; f < frames; ++f) {
        frame::Camera cam;
        if (job.path) {
          const gi::CameraKey k = job.path->at(f);
          cam.eye = k.eye, cam.target = k.target;
          cam.fovYDegrees = job.path->fovYDegrees.value_or(job.fovYDegrees);
        } else if (job.camera)
          cam = *job.camera;
        else
          cam = frame::Camera::framing(meta.bounds, job.fovYDegrees, double(job.width) / job.height,
                                       job.azimuth, job.elevation);
        cam.fitClipPlanes(meta.bounds);
        streaming::View view = cam.view(job.width, job.height);
        view.clip = settings.clip.get();  // nodes the volumes remove whole are never loaded
        streaming::FrameStats st = streamer.update(view);
        if (job.waitComplete) {
          const auto t0 = std::chrono::steady_clock::now();
          while (!st.complete) {
            if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
                job.timeoutSeconds)
              throw Error("render: the view's cut did not load completely within " +
                          std::to_string(job.timeoutSeconds) + " s (" +
                          std::to_string(st.queueLength) + " queued, " +
                          std::to_string(st.inFlight) + " loading)");
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            st = streamer.update(view);
          }
        } else if (!job.path) {
          for (int k = 0; k < job.warmupFrames && !st.complete; ++k) {
            std::this_thread::sleep_for(std::chrono::milliseconds(16));
            st = streamer.update(view);
          }
        }
        frame::DrawTimings timings;
        Image img = renderer.render(streamer.drawList(), store, cam, job.width, job.height,
                                    settings, &timings);
        RenderedFrame rf;
        if (!job.path)
          for (const auto& [px, py] : job.picks) {
            const double x = px + 0.5, y = py + 0.5;
            const std::optional<frame::DepthWindow> depths =
                renderer.depthWindow(x, y, job.pickRadius);
            rf.picks.push_back(depths
                                   ? frame::pickPoint(reader, streamer.drawList(), cam, job.width,
                                                      job.height, x, y, *depths,
                                                      frame::pickOptions(settings, job.pickRadius))
                                   : std::nullopt);
          }
        drawMeasurements(img, cam, job.measurements, unit);
        drawAnnotations(img, cam, job.annotations);
        rf.file = job.path ? frameFile(job.output, f) : job.output;
        rf.stats = st;
        rf.msDraw = timings.msDraw;
        rf.complete = st.complete;
        writeImage(img, rf.file);
        if (csv) {
          csv << f << ',' << rf.file << ',' << (st.complete ? 1 : 0) << ',' << st.cutNodes << ','
              << st.cutPoints << ',' << st.drawNodes << ',' << st.drawPoints << ','
              << st.residentNodes << ',' << st.residentBytes << ',' << st.uploads << ','
              << st.uploadBytes << ',' << st.evictions << ',' << st.cancelled << ','
              << st.queueLength << ',' << st.inFlight << ',' << st.bytesRead << ',' << st.badNodes
              << ',' << st.msCutSelection << ',' << st.msUpload << ',' << st.msUpdate << ','
              << rf.msDraw << '\n';
        }
        if (!job.quiet)
          std::printf("  %s  %dx%d px, %llu points in %u nodes%s, draw %.1f ms\n", rf.file.c_str(),
                      job.width, job.height, (unsigned long long)st.drawPoints, st.drawNodes,
                      st.complete ? "" : " (cut not complete)", rf.msDraw);
        out.push_back(rf);
      }
    }  // the streamer releases its nodes while the store and context live
    return out;
  }
}

}  // namespace nestlight::viewer
