#include "tools.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/octree/attribute.h"
#include "nestlight/octree/crs.h"
#include "nestlight/octree/error.h"
#include "nestlight/viewer/annotations.h"

namespace nestlight::viewer {

namespace {

struct ToolName {
  HeritageTools::Tool tool;
  const char* name;
  const char* label;
};
const ToolName kTools[] = {
    {HeritageTools::Tool::None, "none", "none (orbit)"},
    {HeritageTools::Tool::Pick, "pick", "pick a point"},
    {HeritageTools::Tool::Distance, "distance", "distance"},
    {HeritageTools::Tool::Polyline, "polyline", "polyline length"},
    {HeritageTools::Tool::Area, "area", "polygon area"},
    {HeritageTools::Tool::Height, "height", "height difference"},
    {HeritageTools::Tool::Angle, "angle", "angle"},
    {HeritageTools::Tool::Annotate, "annotate", "annotate"},
    {HeritageTools::Tool::ClipPolygon, "clip-polygon", "clipping polygon"},
    {HeritageTools::Tool::Profile, "profile", "profile (two clicks)"},
};

std::optional<Measurement::Kind> kindOf(HeritageTools::Tool t) {
  using T = HeritageTools::Tool;
  using K = Measurement::Kind;
  switch (t) {
    case T::Distance:
      return K::Distance;
    case T::Polyline:
      return K::Polyline;
    case T::Area:
      return K::Area;
    case T::Height:
      return K::Height;
    case T::Angle:
      return K::Angle;
    default:
      return std::nullopt;
  }
}

// Points that take a fixed count finish by themselves; polylines and areas by "finish".
bool fixedCount(Measurement::Kind k) {
  return k == Measurement::Kind::Distance || k == Measurement::Kind::Height ||
         k == Measurement::Kind::Angle;
}

ImVec2 toImVec(const glm::dvec2& p) {
  return ImVec2(float(p.x), float(p.y));
}

}  // namespace

HeritageTools::HeritageTools(const ViewerOptions& opt, OctreeReader& reader)
    : opt_(opt),
      reader_(reader),
      annotations_(opt.annotations),
      clipping_(),
      stateFile_(opt.stateFile.empty() ? "view.json" : opt.stateFile) {
  unit_ = describeCrs(reader.metadata().crs).unitSymbol();
  profileWidth_ = std::max(reader.metadata().cubeWorldSize() * 0.01, 1e-3);
  if (opt.settings.clip) clipping_ = *opt.settings.clip;
  measurements_ = opt.measurements;
  // Loaded vertices are where they were saved: nothing to refine towards.
  for (const Measurement& m : measurements_) {
    std::vector<Vertex> v(m.points.size());
    for (size_t i = 0; i < v.size(); ++i) v[i].target = m.points[i];
    vertices_.push_back(std::move(v));
  }
}

std::vector<std::string> HeritageTools::toolNames() {
  std::vector<std::string> n;
  for (const ToolName& t : kTools) n.push_back(t.name);
  return n;
}

void HeritageTools::setTool(const std::string& name) {
  for (const ToolName& t : kTools)
    if (name == t.name) {
      tool_ = t.tool;
      placing_ = false;
      return;
    }
  std::string all;
  for (const ToolName& t : kTools) all += (all.empty() ? "" : ", ") + std::string(t.name);
  throw Error("--tool: unknown tool '" + name + "' (" + all + ")");
}

bool HeritageTools::click(frame::PointView& view, const std::vector<streaming::DrawNode>& nodes,
                          const frame::Camera& camera, int width, int height, double x, double y,
                          const frame::RenderSettings& settings) {
  const int radius = 4;
  const std::optional<frame::DepthWindow> depths = view.depthWindow(x, y, radius);
  const std::optional<frame::PickedPoint> p =
      depths ? frame::pickPoint(reader_, nodes, camera, width, height, x, y, *depths,
                                frame::pickOptions(settings, radius))
             : std::nullopt;
  if (!p) {
    status = "nothing under the cursor";
    return false;
  }
  lastPick_ = p;
  // The surface under the cursor: the ray through the pixel at the depth drawn there (the picked
  // point's own depth over background pixels between splats).
  double depth = depths->at(int(std::floor(x)), int(std::floor(y)));
  if (!std::isfinite(depth)) depth = p->depth;
  const double tanY = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
  const glm::dvec3 v((2 * x / width - 1) * tanY * width / height * depth,
                     (1 - 2 * y / height) * tanY * depth, -depth);
  const glm::dvec3 w = camera.eye + glm::transpose(glm::dmat3(camera.viewRotation())) * v;
  place(*p, Vec3d{w.x, w.y, w.z});
  if (profilePending_) {
    profilePending_ = false;
    computeProfile(nodes, settings.clip.get());
  }
  return true;
}

void HeritageTools::computeProfile(const std::vector<streaming::DrawNode>& nodes,
                                   const ClipSet* clip) {
  profile_.clear();
  if (profileLine_.size() != 2 || profileLine_[0] == profileLine_[1]) return;
  const ClipVolume corridor = ClipVolume::corridor(profileLine_, profileWidth_);
  const Metadata& meta = reader_.metadata();
  const int rgb = meta.layout.find(attr::kRgb);
  const double zLo = meta.bounds.min.z, zSpan = std::max(meta.bounds.max.z - zLo, 1e-9);
  for (const streaming::DrawNode& n : nodes) {
    if (corridor.overlap(n.worldBounds) == Overlap::None) continue;
    const PointBuffer buf = reader_.readNode(n.key);
    for (size_t i = 0; i < buf.size(); ++i) {
      const Vec3d p = meta.worldPoint(&buf.pos[3 * i]);
      if (!corridor.contains(p) || (clip && !clip->keeps(p))) continue;
      uint32_t colour;
      if (rgb >= 0) {
        uint16_t c[3];
        std::memcpy(c, buf.attrs.data() + i * buf.stride + meta.layout.offset(size_t(rgb)), 6);
        colour = IM_COL32(c[0] >> 8, c[1] >> 8, c[2] >> 8, 255);
      } else {
        colour = ImU32(frame::elevationRamp((p.z - zLo) / zSpan));
      }
      profile_.push_back({float(corridor.along(p)), float(p.z), colour});
    }
  }
  char b[160];
  std::snprintf(b, sizeof b, ": %zu points of the resident cut, %.3f %s long", profile_.size(),
                corridor.length(), unit_.c_str());
  status += b;
}

// The section in its own window: distance along the line against height at true scale.
void HeritageTools::profilePanel() {
  if (profileLine_.size() != 2) return;
  ImGui::SetNextWindowSize(ImVec2(520, 260), ImGuiCond_FirstUseEver);
  ImGui::Begin("profile");
  const double len =
      std::hypot(profileLine_[1][0] - profileLine_[0][0], profileLine_[1][1] - profileLine_[0][1]);
  float zLo = INFINITY, zHi = -INFINITY;
  for (const ProfilePoint& p : profile_) zLo = std::min(zLo, p.z), zHi = std::max(zHi, p.z);
  ImGui::Text("%zu points, %.3f %s along, heights %.3f to %.3f", profile_.size(), len,
              unit_.c_str(), profile_.empty() ? 0.0 : double(zLo),
              profile_.empty() ? 0.0 : double(zHi));
  const ImVec2 at = ImGui::GetCursorScreenPos();
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float w = std::max(avail.x, 50.0f),
              h = std::max(avail.y - ImGui::GetFrameHeight() * 2, 40.0f);
  ImDrawList* d = ImGui::GetWindowDrawList();
  d->AddRectFilled(at, ImVec2(at.x + w, at.y + h), IM_COL32(20, 20, 26, 255));
  if (!profile_.empty() && len > 0) {
    // One scale for both axes (true shape), fitted to the region.
    const double span = std::max(double(zHi - zLo), 1e-9);
    const double scale = std::min(w / len, h / span);
    for (const ProfilePoint& p : profile_) {
      const float x = at.x + float(p.along * scale), y = at.y + h - float((p.z - zLo) * scale);
      d->AddRectFilled(ImVec2(x, y), ImVec2(x + 2, y + 2), p.colour);
    }
  }
  ImGui::Dummy(ImVec2(w, h));
  // Every point of the corridor, from the whole octree, is the command line's.
  char cmd[512];
  std::snprintf(cmd, sizeof cmd,
                "nestlight profile %s --line %.3f,%.3f,%.3f,%.3f --width %.3f -o section.las "
                "-o section.svg",
                opt_.octree.string().c_str(), profileLine_[0][0], profileLine_[0][1],
                profileLine_[1][0], profileLine_[1][1], profileWidth_);
  ImGui::InputText("every point", cmd, sizeof cmd, ImGuiInputTextFlags_ReadOnly);
  ImGui::End();
}

void HeritageTools::place(const frame::PickedPoint& p, const Vec3d& target) {
  const std::string coords = p.coordinates(reader_.metadata().scale) + " " + unit_;
  if (tool_ == Tool::Pick || tool_ == Tool::None) {
    status = "picked " + coords;
    return;
  }
  if (tool_ == Tool::Annotate) {
    annotations_.push_back({p.position, title_[0] ? title_ : "note", ""});
    status = "annotation at " + coords;
    return;
  }
  if (tool_ == Tool::Profile) {
    if (profileLine_.size() == 2) profileLine_.clear();
    profileLine_.push_back({p.position.x, p.position.y});
    profilePending_ = profileLine_.size() == 2;
    status = profileLine_.size() == 1 ? "profile from " + coords : "profile to " + coords;
    return;
  }
  if (tool_ == Tool::ClipPolygon) {
    clipPolygon_.push_back({p.position.x, p.position.y});
    status = "clipping polygon: " + std::to_string(clipPolygon_.size()) + " points";
    return;
  }
  const Measurement::Kind kind = *kindOf(tool_);
  if (!placing_) {
    Measurement m;
    m.kind = kind;
    m.name =
        std::string(measurementKindName(kind)) + " " + std::to_string(measurements_.size() + 1);
    measurements_.push_back(m);
    vertices_.emplace_back();
    placing_ = true;
  }
  Measurement& m = measurements_.back();
  m.points.push_back(p.position);
  Vertex v;
  v.target = target;
  const double dx = p.position.x - target.x, dy = p.position.y - target.y,
               dz = p.position.z - target.z;
  v.snapDistance = std::sqrt(dx * dx + dy * dy + dz * dz);
  vertices_.back().push_back(v);
  if (fixedCount(kind) && m.points.size() >= Measurement::minimumPoints(kind)) placing_ = false;
  status = m.complete() ? m.describe(unit_) : "placed " + coords;
}

void HeritageTools::refine(const std::vector<streaming::DrawNode>& nodes,
                           const frame::RenderSettings& settings) {
  size_t sig = nodes.size();
  for (const auto& n : nodes) sig = sig * 1000003u ^ NodeKeyHash {}(n.key);
  if (sig == drawnSignature_) return;
  drawnSignature_ = sig;
  for (size_t m = 0; m < measurements_.size(); ++m)
    for (size_t i = 0; i < vertices_[m].size(); ++i) {
      Vertex& v = vertices_[m][i];
      if (v.snapDistance <= 0) continue;  // on a point already (or loaded from a file)
      const auto q = frame::nearestPoint(reader_, nodes, v.target, v.snapDistance,
                                         settings.clip.get(), &v.searched);
      if (q && q->depth < v.snapDistance) {
        measurements_[m].points[i] = q->position;
        v.snapDistance = q->depth;
      }
    }
}

void HeritageTools::finish(frame::RenderSettings& settings) {
  if (tool_ == Tool::ClipPolygon) {
    if (clipPolygon_.size() >= 3) {
      try {
        ClipVolume c = ClipVolume::polygon(clipPolygon_);
        c.validate("", "the clipping polygon");
        clipping_.volumes.push_back(c);
        settings.clip = std::make_shared<const ClipSet>(clipping_);
        status = "clipping polygon added";
      } catch (const Error& e) {
        status = e.what();
      }
    }
    clipPolygon_.clear();
    return;
  }
  if (placing_ && !measurements_.empty() && !measurements_.back().complete()) {
    measurements_.pop_back();
    vertices_.pop_back();
  }
  placing_ = false;
}

void HeritageTools::panel(frame::RenderSettings& settings, const frame::Camera& camera,
                          double extent) {
  if (!ImGui::CollapsingHeader("tools", ImGuiTreeNodeFlags_DefaultOpen)) return;
  int current = 0;
  std::string items;
  for (size_t i = 0; i < std::size(kTools); ++i) {
    items += std::string(kTools[i].label) + '\0';
    if (kTools[i].tool == tool_) current = int(i);
  }
  if (ImGui::Combo("tool (click)", &current, items.c_str())) {
    finish(settings);
    tool_ = kTools[current].tool;
  }
  if (tool_ == Tool::Annotate) ImGui::InputText("title", title_, sizeof title_);
  if (tool_ == Tool::Profile) {
    ImGui::DragScalar("profile width", ImGuiDataType_Double, &profileWidth_,
                      float(std::max(extent * 0.0005, 1e-5)));
    profileWidth_ = std::max(profileWidth_, 1e-6);
  }
  if (tool_ == Tool::Polyline || tool_ == Tool::Area || tool_ == Tool::ClipPolygon) {
    if (ImGui::Button("finish (Enter)")) finish(settings);
  }
  if (!status.empty()) ImGui::TextWrapped("%s", status.c_str());
  profilePanel();
  if (lastPick_) {
    ImGui::TextUnformatted(
        (lastPick_->coordinates(reader_.metadata().scale) + " " + unit_).c_str());
    ImGui::TextDisabled("%s", frame::describeAttributes(lastPick_->attributes).c_str());
  }
  // Measurements, each with its value and a delete button.
  for (size_t i = 0; i < measurements_.size(); ++i) {
    const Measurement& m = measurements_[i];
    ImGui::PushID(int(i));
    if (ImGui::SmallButton("x")) {
      measurements_.erase(measurements_.begin() + long(i));
      vertices_.erase(vertices_.begin() + long(i));
      if (i == measurements_.size()) placing_ = false;
      ImGui::PopID();
      break;
    }
    ImGui::SameLine();
    ImGui::Text("%s", m.complete() ? m.describe(unit_).c_str() : "(placing)");
    ImGui::PopID();
  }
  // Clipping volumes: a box around the view's target, edited here.
  bool clipChanged = false;
  if (ImGui::Button("add clipping box")) {
    const double s = std::max(extent * 0.25, 1e-3);
    clipping_.volumes.push_back(
        ClipVolume::box(Vec3d{camera.target.x, camera.target.y, camera.target.z}, Vec3d{s, s, s}));
    clipChanged = true;
  }
  for (size_t i = 0; i < clipping_.volumes.size(); ++i) {
    ClipVolume& v = clipping_.volumes[i];
    ImGui::PushID(int(1000 + i));
    if (ImGui::SmallButton("x")) {
      clipping_.volumes.erase(clipping_.volumes.begin() + long(i));
      clipChanged = true;
      ImGui::PopID();
      break;
    }
    ImGui::SameLine();
    bool outside = v.mode == ClipVolume::Mode::Outside;
    if (ImGui::Checkbox(
            v.kind == ClipVolume::Kind::Box ? "box: remove inside" : "polygon: remove inside",
            &outside)) {
      v.mode = outside ? ClipVolume::Mode::Outside : ClipVolume::Mode::Inside;
      clipChanged = true;
    }
    if (v.kind == ClipVolume::Kind::Box) {
      double c[3] = {v.center.x, v.center.y, v.center.z};
      double size[3] = {2 * v.half.x, 2 * v.half.y, 2 * v.half.z};
      double rot = v.rotationDegrees[2];
      const float speed = float(std::max(extent * 0.002, 1e-4));
      bool edit = ImGui::DragScalarN("centre", ImGuiDataType_Double, c, 3, speed);
      edit |= ImGui::DragScalarN("size", ImGuiDataType_Double, size, 3, speed);
      edit |= ImGui::DragScalar("rotation z", ImGuiDataType_Double, &rot, 0.5f);
      if (edit) {
        const ClipVolume::Mode mode = v.mode;
        v = ClipVolume::box(
            Vec3d{c[0], c[1], c[2]},
            Vec3d{std::max(size[0], 1e-6), std::max(size[1], 1e-6), std::max(size[2], 1e-6)},
            {v.rotationDegrees[0], v.rotationDegrees[1], rot});
        v.mode = mode;
        clipChanged = true;
      }
    }
    ImGui::PopID();
  }
  if (clipChanged)
    settings.clip = clipping_.empty() ? nullptr : std::make_shared<const ClipSet>(clipping_);
  // Annotations.
  for (size_t i = 0; i < annotations_.size(); ++i) {
    ImGui::PushID(int(2000 + i));
    if (ImGui::SmallButton("x")) {
      annotations_.erase(annotations_.begin() + long(i));
      ImGui::PopID();
      break;
    }
    ImGui::SameLine();
    ImGui::Text("note: %s", annotations_[i].title.c_str());
    ImGui::PopID();
  }
}

void HeritageTools::drawOverlay(const frame::Camera& camera, int width, int height) const {
  ImDrawList* d = ImGui::GetBackgroundDrawList();
  const ImU32 line = IM_COL32(50, 230, 255, 255), white = IM_COL32(255, 255, 255, 255),
              box = IM_COL32(12, 12, 18, 190), accent = IM_COL32(255, 190, 25, 255);
  for (const Measurement& m : measurements_) {
    std::vector<glm::dvec2> pts;
    for (const Vec3d& p : m.points)
      if (const auto at = projectToImage(camera, width, height, p)) pts.push_back(*at);
    if (pts.size() != m.points.size()) continue;  // a vertex off screen: values in the panel
    for (size_t i = 0; i + 1 < pts.size(); ++i)
      d->AddLine(toImVec(pts[i]), toImVec(pts[i + 1]), line, 2.0f);
    if (m.kind == Measurement::Kind::Area && pts.size() >= 3)
      d->AddLine(toImVec(pts.back()), toImVec(pts.front()), line, 2.0f);
    for (const auto& p : pts) d->AddCircleFilled(toImVec(p), 3.0f, white);
    if (m.complete()) {
      const std::string text = measurementLabel(m, unit_);
      const ImVec2 at(float(pts.back().x) + 6, float(pts.back().y) + 4);
      const ImVec2 size = ImGui::CalcTextSize(text.c_str());
      d->AddRectFilled(at, ImVec2(at.x + size.x + 6, at.y + size.y + 4), box);
      d->AddText(ImVec2(at.x + 3, at.y + 2), white, text.c_str());
    }
  }
  for (const frame::Annotation& a : annotations_) {
    const auto at = projectToImage(camera, width, height, a.position);
    if (!at) continue;
    d->AddCircle(toImVec(*at), 5.0f, accent, 0, 2.0f);
    const ImVec2 t(float(at->x) + 9, float(at->y) - 22);
    const ImVec2 size = ImGui::CalcTextSize(a.title.c_str());
    d->AddRectFilled(t, ImVec2(t.x + size.x + 6, t.y + size.y + 4), box);
    d->AddText(ImVec2(t.x + 3, t.y + 2), white, a.title.c_str());
    // The text shows while the cursor rests on the label.
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    if (!a.text.empty() && mouse.x >= t.x && mouse.x <= t.x + size.x + 6 && mouse.y >= t.y &&
        mouse.y <= t.y + size.y + 4)
      ImGui::SetTooltip("%s", a.text.c_str());
  }
  if (profileLine_.size() == 2) {
    const auto a = projectToImage(camera, width, height,
                                  Vec3d{profileLine_[0][0], profileLine_[0][1], camera.target.z});
    const auto b = projectToImage(camera, width, height,
                                  Vec3d{profileLine_[1][0], profileLine_[1][1], camera.target.z});
    if (a && b) d->AddLine(toImVec(*a), toImVec(*b), IM_COL32(255, 80, 200, 255), 2.0f);
  }
  for (size_t i = 0; i + 1 < clipPolygon_.size(); ++i) {
    const auto a = projectToImage(camera, width, height,
                                  Vec3d{clipPolygon_[i][0], clipPolygon_[i][1], camera.target.z});
    const auto b =
        projectToImage(camera, width, height,
                       Vec3d{clipPolygon_[i + 1][0], clipPolygon_[i + 1][1], camera.target.z});
    if (a && b) d->AddLine(toImVec(*a), toImVec(*b), accent, 2.0f);
  }
}

void HeritageTools::drawInto(frame::Image& image, const frame::Camera& camera) const {
  drawMeasurements(image, camera, measurements_, unit_);
  drawAnnotations(image, camera, annotations_);
}

frame::ViewState HeritageTools::state(const frame::Camera& camera, frame::ColourMode colour,
                                      const streaming::Budgets& budgets,
                                      const frame::RenderSettings& settings) const {
  frame::ViewState s;
  const Metadata& meta = reader_.metadata();
  s.octree = opt_.octree.string();
  s.octreeBounds = meta.bounds;
  const CrsInfo crs = describeCrs(meta.crs);
  if (crs.known) s.crs = crs.summary();
  s.camera = camera;
  s.colour = colour;
  s.colourLayer = opt_.colourLayer;
  s.budgets = budgets;
  s.settings = settings;
  s.settings.clip.reset();
  s.clipping = clipping_;
  for (const Measurement& m : measurements_)
    if (m.complete()) s.measurements.push_back(m);
  s.annotations = annotations_;
  return s;
}

void HeritageTools::save(const std::string& file, const frame::ViewState& state) {
  try {
    state.save(file);
    stateFile_ = file;
    status = "view saved to " + file;
  } catch (const Error& e) {
    status = e.what();
  }
  std::printf("view: %s\n", status.c_str());
  std::fflush(stdout);
}

}  // namespace nestlight::viewer
