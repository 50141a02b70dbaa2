#include "nestlight/frame/view_state.h"

#include <fstream>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::frame {
namespace {

nlohmann::json vec(const glm::dvec3& v) {
  return {v.x, v.y, v.z};
}
nlohmann::json vec(const Vec3d& v) {
  return {v.x, v.y, v.z};
}
glm::dvec3 dvec(const JsonField& f, double lo = -INFINITY, double hi = INFINITY) {
  const auto a = f.vec3(lo, hi);
  return {a[0], a[1], a[2]};
}

// A parse function that throws on an unknown name (parseColourMode, ...) re-thrown naming the
// field.
template <typename F>
auto named(const JsonField& f, F parse) {
  const std::string s = f.string();
  try {
    return parse(s);
  } catch (const Error& e) {
    f.fail(e.what());
  }
}

}  // namespace

ViewState ViewState::fromJson(const nlohmann::json& j, const std::string& file) {
  const JsonField root(j, "", file);
  root.expectObject({"version", "octree", "camera", "colour", "budgets", "splatting", "clipping",
                     "measurements", "annotations", "gi"});
  ViewState s;
  if (root.has("version")) {
    const JsonField v = root.at("version");
    if (!v.value().is_number_integer() || v.value().get<int64_t>() < 1)
      v.fail("expected a version number");
    if (v.value().get<int64_t>() > kVersion)
      v.fail("version " + std::to_string(v.value().get<int64_t>()) +
             " was written by a newer nestlight (this one reads " + std::to_string(kVersion) + ")");
  }
  if (root.has("octree")) {
    const JsonField o = root.at("octree");
    o.expectObject({"path", "bounds", "crs"});
    if (o.has("path")) s.octree = o.at("path").string();
    if (o.has("crs")) s.crs = o.at("crs").string();
    if (o.has("bounds")) {
      const JsonField b = o.at("bounds");
      if (b.arraySize() != 2) b.fail("expected [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
      const auto lo = b.at(size_t(0)).vec3(), hi = b.at(size_t(1)).vec3();
      Box3d box;
      box.min = {lo[0], lo[1], lo[2]}, box.max = {hi[0], hi[1], hi[2]};
      if (box.empty()) b.fail("the minimum corner lies above the maximum");
      s.octreeBounds = box;
    }
  }
  if (root.has("camera")) {
    const JsonField c = root.at("camera");
    c.expectObject({"eye", "target", "up", "fov"});
    Camera cam;
    cam.eye = dvec(c.at("eye"));
    cam.target = dvec(c.at("target"));
    if (c.has("up")) cam.up = dvec(c.at("up"));
    if (c.has("fov")) cam.fovYDegrees = c.at("fov").number(1, 179);
    if (cam.eye == cam.target) c.at("target").fail("the target is the eye: no direction to look");
    if (glm::length(cam.up) == 0) c.at("up").fail("expected a non-zero vector");
    s.camera = cam;
  }
  if (root.has("colour")) {
    const JsonField c = root.at("colour");
    c.expectObject({"mode", "layer"});
    if (c.has("mode")) s.colour = named(c.at("mode"), parseColourMode);
    if (c.has("layer")) s.colourLayer = c.at("layer").string();
  }
  if (root.has("budgets")) {
    const JsonField b = root.at("budgets");
    b.expectObject({"points", "gpu_bytes", "upload_bytes", "loaders", "spacing_pixels"});
    if (b.has("points")) s.budgets.points = b.at("points").count();
    if (b.has("gpu_bytes")) s.budgets.gpuBytes = b.at("gpu_bytes").count();
    if (b.has("upload_bytes")) s.budgets.uploadBytesPerFrame = b.at("upload_bytes").count();
    if (b.has("loaders")) s.budgets.loaderThreads = int(b.at("loaders").integer(1, 64));
    if (b.has("spacing_pixels")) s.budgets.spacingPixels = b.at("spacing_pixels").number(0, 1e4);
  }
  if (root.has("splatting")) {
    const JsonField p = root.at("splatting");
    p.expectObject({"rasteriser", "splatting", "size_scale", "fixed_point_size", "min_point_size",
                    "max_point_size", "round", "edl", "edl_radius", "exposure", "background"});
    RenderSettings& r = s.settings;
    if (p.has("rasteriser")) r.rasteriser = named(p.at("rasteriser"), parseRasteriser);
    if (p.has("splatting")) r.splatting = named(p.at("splatting"), parseSplatting);
    if (p.has("size_scale")) r.sizeScale = float(p.at("size_scale").number(0.01, 100));
    if (p.has("fixed_point_size"))
      r.fixedPointSize = float(p.at("fixed_point_size").number(0, 256));
    if (p.has("min_point_size")) r.minPointSize = float(p.at("min_point_size").number(0.5, 256));
    if (p.has("max_point_size")) r.maxPointSize = float(p.at("max_point_size").number(0.5, 256));
    if (r.minPointSize > r.maxPointSize) p.at("min_point_size").fail("above max_point_size");
    if (p.has("round")) r.roundPoints = p.at("round").boolean();
    if (p.has("edl")) r.edlStrength = float(p.at("edl").number(0, 100));
    if (p.has("edl_radius"))
      r.edlRadius = float(p.at("edl_radius").number(0, RenderSettings::kMaxEdlRadius));
    if (p.has("exposure")) r.exposureStops = float(p.at("exposure").number(-32, 32));
    if (p.has("background")) r.background = glm::vec3(dvec(p.at("background"), 0, 1));
  }
  if (root.has("clipping"))
    s.clipping = ClipSet::fromJson(nlohmann::json{{"clipping", j["clipping"]}}, file);
  if (root.has("measurements")) {
    const JsonField m = root.at("measurements");
    for (size_t i = 0, n = m.arraySize(); i < n; ++i)
      s.measurements.push_back(Measurement::fromJson(m.at(i)));
  }
  if (root.has("annotations")) {
    const JsonField a = root.at("annotations");
    for (size_t i = 0, n = a.arraySize(); i < n; ++i) {
      const JsonField e = a.at(i);
      e.expectObject({"position", "title", "text"});
      Annotation an;
      const auto p = e.at("position").vec3();
      an.position = {p[0], p[1], p[2]};
      an.title = e.at("title").string();
      if (an.title.empty()) e.at("title").fail("expected a title (the label shown at the point)");
      if (e.has("text")) an.text = e.at("text").string();
      s.annotations.push_back(std::move(an));
    }
  }
  if (root.has("gi")) {
    const JsonField g = root.at("gi");
    g.expectObject({"method", "parameters"});
    g.at("method").string();
    if (g.has("parameters") && !g.at("parameters").value().is_object())
      g.at("parameters").fail("expected an object");
    s.gi = j["gi"];
  }
  return s;
}

ViewState ViewState::load(const std::filesystem::path& file) {
  return fromJson(readJsonFile(file), file.string());
}

nlohmann::json ViewState::toJson() const {
  nlohmann::json j{{"version", kVersion}};
  if (!octree.empty() || octreeBounds || !crs.empty()) {
    nlohmann::json o = nlohmann::json::object();
    if (!octree.empty()) o["path"] = octree;
    if (octreeBounds) o["bounds"] = {vec(octreeBounds->min), vec(octreeBounds->max)};
    if (!crs.empty()) o["crs"] = crs;
    j["octree"] = o;
  }
  if (camera)
    j["camera"] = {{"eye", vec(camera->eye)},
                   {"target", vec(camera->target)},
                   {"up", vec(camera->up)},
                   {"fov", camera->fovYDegrees}};
  nlohmann::json colourJson{{"layer", colourLayer}};
  if (colour) colourJson["mode"] = colourModeName(*colour);
  j["colour"] = colourJson;
  j["budgets"] = {{"points", budgets.points},
                  {"gpu_bytes", budgets.gpuBytes},
                  {"upload_bytes", budgets.uploadBytesPerFrame},
                  {"loaders", budgets.loaderThreads},
                  {"spacing_pixels", budgets.spacingPixels}};
  const RenderSettings& r = settings;
  j["splatting"] = {{"rasteriser", rasteriserName(r.rasteriser)},
                    {"splatting", splattingName(r.splatting)},
                    {"size_scale", r.sizeScale},
                    {"fixed_point_size", r.fixedPointSize},
                    {"min_point_size", r.minPointSize},
                    {"max_point_size", r.maxPointSize},
                    {"round", r.roundPoints},
                    {"edl", r.edlStrength},
                    {"edl_radius", r.edlRadius},
                    {"exposure", r.exposureStops},
                    {"background", {r.background.x, r.background.y, r.background.z}}};
  j["clipping"] = clipping.toJson();
  nlohmann::json m = nlohmann::json::array();
  for (const Measurement& x : measurements) m.push_back(x.toJson());
  j["measurements"] = m;
  nlohmann::json a = nlohmann::json::array();
  for (const Annotation& x : annotations)
    a.push_back({{"position", vec(x.position)}, {"title", x.title}, {"text", x.text}});
  j["annotations"] = a;
  if (!gi.is_null()) j["gi"] = gi;
  return j;
}

void ViewState::save(const std::filesystem::path& file) const {
  const std::filesystem::path tmp = file.string() + ".tmp";
  {
    std::ofstream f(tmp);
    f << toJson().dump(1) << "\n";
    if (!f) throw Error(file.string(), "", "cannot write the view state");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) throw Error(file.string(), "", "cannot rename " + tmp.string() + ": " + ec.message());
}

std::string ViewState::boundsWarning(const Box3d& b) const {
  if (!octreeBounds || b.empty()) return "";
  const Box3d& s = *octreeBounds;
  const bool overlap = s.min.x <= b.max.x && b.min.x <= s.max.x && s.min.y <= b.max.y &&
                       b.min.y <= s.max.y && s.min.z <= b.max.z && b.min.z <= s.max.z;
  if (overlap) return "";
  char text[512];
  std::snprintf(text, sizeof text,
                "the view state was saved from %s, whose bounds [%.3f %.3f %.3f] - [%.3f %.3f "
                "%.3f] do not overlap this octree's [%.3f %.3f %.3f] - [%.3f %.3f %.3f]: its "
                "camera, clipping volumes, measurements and annotations may show nothing",
                octree.empty() ? "another octree" : octree.c_str(), s.min.x, s.min.y, s.min.z,
                s.max.x, s.max.y, s.max.z, b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z);
  return text;
}

}  // namespace nestlight::frame
