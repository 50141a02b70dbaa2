#include "nestlight/viewer/headless.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/gl/context.h"

namespace nestlight::viewer {

namespace fs = std::filesystem;

namespace {

glm::dvec3 vec3Field(const nlohmann::json& j, const std::string& file, const std::string& field) {
  if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
    throw Error(file, field, "expected an array of three numbers");
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

std::string frameFile(const std::string& pattern, int frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%04d", frame);
  const auto at = pattern.find("%04d");
  if (at != std::string::npos) return pattern.substr(0, at) + buf + pattern.substr(at + 4);
  const fs::path p(pattern);
  return (p.parent_path() / (p.stem().string() + "_" + buf + p.extension().string())).string();
}

}  // namespace

CameraPath CameraPath::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path, "", "cannot open camera path");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path, Error::atByte(e.byte), "invalid JSON");
  }
  CameraPath p;
  if (j.contains("fps")) {
    if (!j["fps"].is_number() || !(j["fps"].get<double>() > 0)) throw Error(path, "fps", "must be a positive number");
    p.fps = j["fps"].get<double>();
  }
  if (j.contains("fov")) {
    if (!j["fov"].is_number() || !(j["fov"].get<double>() > 0 && j["fov"].get<double>() < 180))
      throw Error(path, "fov", "must be a number of degrees in (0, 180)");
    p.fovYDegrees = j["fov"].get<double>();
  }
  if (!j.contains("keyframes") || !j["keyframes"].is_array() || j["keyframes"].empty())
    throw Error(path, "keyframes", "a non-empty array of {time, eye, target} is required");
  for (size_t i = 0; i < j["keyframes"].size(); ++i) {
    const auto& k = j["keyframes"][i];
    const std::string f = "keyframes[" + std::to_string(i) + "]";
    if (!k.is_object()) throw Error(path, f, "expected an object");
    Key key;
    if (!k.contains("time") || !k["time"].is_number()) throw Error(path, f + ".time", "a number of seconds is required");
    key.time = k["time"].get<double>();
    if (!p.keys.empty() && !(key.time > p.keys.back().time))
      throw Error(path, f + ".time", "times must increase");
    if (!k.contains("eye")) throw Error(path, f + ".eye", "required");
    if (!k.contains("target")) throw Error(path, f + ".target", "required");
    key.eye = vec3Field(k["eye"], path, f + ".eye");
    key.target = vec3Field(k["target"], path, f + ".target");
    if (glm::length(key.eye - key.target) <= 0) throw Error(path, f, "eye and target coincide");
    p.keys.push_back(key);
  }
  return p;
}

int CameraPath::frames() const {
  if (keys.size() < 2) return 1;
  return static_cast<int>(std::floor((keys.back().time - keys.front().time) * fps)) + 1;
}

Camera CameraPath::at(int frame) const {
  Camera c;
  c.fovYDegrees = fovYDegrees;
  const double t = keys.front().time + frame / fps;
  size_t i = 0;
  while (i + 2 < keys.size() && t > keys[i + 1].time) ++i;
  if (keys.size() == 1) {
    c.eye = keys[0].eye, c.target = keys[0].target;
    return c;
  }
  const double u = std::clamp((t - keys[i].time) / (keys[i + 1].time - keys[i].time), 0.0, 1.0);
  c.eye = glm::mix(keys[i].eye, keys[i + 1].eye, u);
  c.target = glm::mix(keys[i].target, keys[i + 1].target, u);
  return c;
}

std::vector<RenderedFrame> renderHeadless(const RenderJob& job) {
  OctreeReader reader(job.octree);  // before any GL work: a bad octree fails here
  const Metadata& meta = reader.metadata();
  const frame::ColourMode mode = job.colour ? *job.colour
                                     : (meta.layout.has(attr::kRgb) ? frame::ColourMode::Rgb : frame::ColourMode::Elevation);
  const auto modes = frame::availableColourModes(meta);
  if (std::find(modes.begin(), modes.end(), mode) == modes.end())
    throw Error(job.octree.string(), "", std::string("the scan has no attribute for colour mode '") +
                                             frame::colourModeName(mode) + "'");
  auto context = gl::createHeadlessContext();
  if (!job.quiet) std::printf("render: %s\n", context->description().c_str());
  {
    frame::GlNodeStore store(meta, mode);
    FrameRenderer renderer;
    std::vector<RenderedFrame> out;
    {
      streaming::Streamer streamer(reader, store, job.budgets);
      std::ofstream csv;
      if (!job.statsCsv.empty()) {
        csv.open(job.statsCsv);
        if (!csv) throw Error(job.statsCsv, "", "cannot write stats CSV");
        csv << "frame,file,complete,cut_nodes,cut_points,draw_nodes,draw_points,resident_nodes,resident_bytes,"
               "uploads,upload_bytes,evictions,cancelled,queue,in_flight,bytes_read,bad_nodes,ms_cut,ms_upload,"
               "ms_update,ms_draw\n";
      }
      const int frames = job.path ? job.path->frames() : 1;
      for (int f = 0; f < frames; ++f) {
        Camera cam;
        if (job.path) cam = job.path->at(f);
        else if (job.camera) cam = *job.camera;
        else cam = Camera::framing(meta.bounds, job.fovYDegrees, double(job.width) / job.height, job.azimuth, job.elevation);
        cam.fitClipPlanes(meta.bounds);
        const streaming::View view = cam.view(job.width, job.height);
        streaming::FrameStats st = streamer.update(view);
        if (job.waitComplete) {
          const auto t0 = std::chrono::steady_clock::now();
          while (!st.complete) {
            if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > job.timeoutSeconds)
              throw Error("render: the view's cut did not load completely within " +
                          std::to_string(job.timeoutSeconds) + " s (" + std::to_string(st.queueLength) +
                          " queued, " + std::to_string(st.inFlight) + " loading)");
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            st = streamer.update(view);
          }
        } else if (!job.path) {
          for (int k = 0; k < job.warmupFrames && !st.complete; ++k) {
            std::this_thread::sleep_for(std::chrono::milliseconds(16));
            st = streamer.update(view);
          }
        }
        DrawTimings timings;
        Image img = renderer.render(streamer.drawList(), store, cam, job.width, job.height, job.settings, &timings);
        RenderedFrame rf;
        rf.file = job.path ? frameFile(job.output, f) : job.output;
        rf.stats = st;
        rf.msDraw = timings.msDraw;
        rf.complete = st.complete;
        writeImage(img, rf.file);
        if (csv) {
          csv << f << ',' << rf.file << ',' << (st.complete ? 1 : 0) << ',' << st.cutNodes << ',' << st.cutPoints << ','
              << st.drawNodes << ',' << st.drawPoints << ',' << st.residentNodes << ',' << st.residentBytes << ','
              << st.uploads << ',' << st.uploadBytes << ',' << st.evictions << ',' << st.cancelled << ','
              << st.queueLength << ',' << st.inFlight << ',' << st.bytesRead << ',' << st.badNodes << ','
              << st.msCutSelection << ',' << st.msUpload << ',' << st.msUpdate << ',' << rf.msDraw << '\n';
        }
        if (!job.quiet)
          std::printf("  %s  %dx%d px, %llu points in %u nodes%s, draw %.1f ms\n", rf.file.c_str(), job.width,
                      job.height, (unsigned long long)st.drawPoints, st.drawNodes,
                      st.complete ? "" : " (cut not complete)", rf.msDraw);
        out.push_back(rf);
      }
    }  // the streamer releases its nodes while the store and context live
    return out;
  }
}

}  // namespace nestlight::viewer
