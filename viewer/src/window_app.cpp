#include "nestlight/viewer/window_app.h"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>

#include "method_view.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/image.h"
#include "tools.h"

namespace nestlight::viewer {

// The point view's types (nestlight/frame/point_view.h, camera.h), which the window drives.
using frame::Camera;
using frame::CameraController;
using frame::DrawTimings;
using frame::PointView;
using frame::Rasteriser;
using frame::RenderSettings;
using frame::Splatting;

namespace {
// The world bounds of a scene's meshes: what a scene without a scan is framed by.
Box3d meshBounds(const gi::Scene& scene) {
  Box3d box;
  for (const gi::SceneMesh& m : scene.meshes) {
    const gi::TriangleMesh mesh = gi::readMesh(m.path.string());
    for (const glm::vec3& p : mesh.positions) {
      const glm::dvec4 w = m.worldFromObject * glm::dvec4(glm::dvec3(p), 1.0);
      if (std::isfinite(w.x) && std::isfinite(w.y) && std::isfinite(w.z)) box.extend(w.x, w.y, w.z);
    }
  }
  return box;
}
// The colourings the scan offers, the one to start with, and the HDR layer when there is one.
struct ScanColours {
  std::vector<frame::ColourMode> modes;
  frame::ColourMode mode{};
  std::shared_ptr<const ColourLayerReader> hdrLayer;
};

ScanColours scanColours(const ViewerOptions& opt, const Metadata& meta) {
  ScanColours c;
  std::vector<frame::ColourMode>& modes = c.modes;
  frame::ColourMode& mode = c.mode;
  std::shared_ptr<const ColourLayerReader>& hdrLayer = c.hdrLayer;
  modes = frame::availableColourModes(meta, opt.colourLayer);
  mode = opt.colour ? *opt.colour : modes.front();
  if (std::find(modes.begin(), modes.end(), mode) == modes.end())
    throw Error(
        opt.octree.string(), "",
        std::string("the scan has nothing to show for colour mode '") +
            frame::colourModeName(mode) + "'" +
            (mode == frame::ColourMode::Hdr ? " (no colour layer '" + opt.colourLayer + "')" : ""));
  if (meta.layer(opt.colourLayer)) {
    try {
      hdrLayer = std::make_shared<const ColourLayerReader>(opt.octree, meta, opt.colourLayer);
    } catch (const Error& e) {
      if (mode == frame::ColourMode::Hdr) throw;
      // A damaged layer the user did not ask for: the scan still opens, without that colouring.
      std::fprintf(stderr, "view: %s; colouring hdr unavailable\n", e.what());
      modes.erase(std::find(modes.begin(), modes.end(), frame::ColourMode::Hdr));
    }
  }
  return c;
}

// Mouse and keyboard move the camera, unless the panel has them.
void moveCamera(CameraController& cc, GLFWwindow* w, const ImGuiIO& io, double dx, double dy,
                double dt) {
  if (!io.WantCaptureMouse) {
    if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
      cc.yaw -= dx * 0.3;
      cc.pitch = std::clamp(cc.pitch + dy * 0.3, -89.0, 89.0);
    }
    if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS) {
      const Camera c = cc.camera();
      const glm::dvec3 f = glm::normalize(c.target - c.eye);
      const glm::dvec3 r = glm::normalize(glm::cross(f, c.up)), u = glm::cross(r, f);
      const double k = cc.distance * 0.0015;
      cc.target += (-r * dx + u * dy) * k;
    }
    if (io.MouseWheel != 0) cc.distance *= std::pow(0.85, io.MouseWheel);
  }
  if (!io.WantCaptureKeyboard && cc.mode == CameraController::Mode::Fly) {
    const Camera c = cc.camera();
    const glm::dvec3 f = glm::normalize(c.target - c.eye);
    const glm::dvec3 r = glm::normalize(glm::cross(f, c.up));
    double v = cc.speed * dt * (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ? 5.0 : 1.0);
    glm::dvec3 move(0);
    if (glfwGetKey(w, GLFW_KEY_W) == GLFW_PRESS) move += f;
    if (glfwGetKey(w, GLFW_KEY_S) == GLFW_PRESS) move -= f;
    if (glfwGetKey(w, GLFW_KEY_D) == GLFW_PRESS) move += r;
    if (glfwGetKey(w, GLFW_KEY_A) == GLFW_PRESS) move -= r;
    if (glfwGetKey(w, GLFW_KEY_E) == GLFW_PRESS) move += c.up;
    if (glfwGetKey(w, GLFW_KEY_Q) == GLFW_PRESS) move -= c.up;
    cc.target += move * v;  // the eye follows: it sits at target + direction * distance
  }
}

// A colour bar with its two ends' values under it: the legend of a scalar colouring.
void legend(const std::function<ImU32(double)>& colour, int segments, const char* lo,
            const char* hi, const char* caption) {
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const ImVec2 at = ImGui::GetCursorScreenPos();
  const float w = ImGui::CalcItemWidth(), h = ImGui::GetFontSize();
  for (int i = 0; i < segments; ++i) {
    const float x0 = at.x + w * i / segments, x1 = at.x + w * (i + 1) / segments;
    const ImU32 c0 = colour(double(i) / segments), c1 = colour(double(i + 1) / segments);
    draw->AddRectFilledMultiColor(ImVec2(x0, at.y), ImVec2(x1, at.y + h), c0, c1, c1, c0);
  }
  ImGui::Dummy(ImVec2(w, h));
  ImGui::TextUnformatted(lo);
  ImGui::SameLine(std::max(w - ImGui::CalcTextSize(hi).x, ImGui::CalcTextSize(lo).x + 8));
  ImGui::TextUnformatted(hi);
  ImGui::SameLine();
  ImGui::TextDisabled("%s", caption);
}

// The elevation and intensity colourings' scales: which colour is which height or return.
void colourLegend(frame::ColourMode mode, const Metadata& meta) {
  char lo[64], hi[64];
  if (mode == frame::ColourMode::Elevation) {
    std::snprintf(lo, sizeof lo, "%.2f", meta.bounds.min.z);
    std::snprintf(hi, sizeof hi, "%.2f", meta.bounds.max.z);
    legend([](double t) { return ImU32(frame::elevationRamp(t)); }, 4, lo, hi, "z");
  } else if (mode == frame::ColourMode::Intensity) {
    legend(
        [](double t) {
          const auto g = uint32_t(frame::intensityGrey(t * 65535.0) * 255.0 + 0.5);
          return ImU32(g | (g << 8) | (g << 16) | (255u << 24));
        },
        16, "0", "65535", "intensity (square root)");
  }
}

// The point view's part of the panel: rasteriser, colouring (with its legend), splatting, budgets
// and the streaming figures. A colouring change restarts the residency (colours are baked on
// upload).
void pointsPanel(RenderSettings& settings, ScanColours& colours, OctreeReader& reader,
                 frame::GlNodeStore& store, std::unique_ptr<streaming::Streamer>& streamer,
                 streaming::Budgets& budgets, const streaming::FrameStats& st,
                 const DrawTimings& timings) {
  std::vector<frame::ColourMode>& modes = colours.modes;
  frame::ColourMode& mode = colours.mode;
  int raster = settings.rasteriser == Rasteriser::Points ? 0 : 1;
  if (ImGui::Combo("rasteriser", &raster, "GL_POINTS\0compute\0")) {
    settings.rasteriser = raster == 0 ? Rasteriser::Points : Rasteriser::Compute;
    settings.fixedPointSize = raster == 1 ? 1.f : 0.f;
  }
  int modeIndex = int(std::find(modes.begin(), modes.end(), mode) - modes.begin());
  std::string names;
  for (frame::ColourMode m : modes) names += std::string(frame::colourModeName(m)) + '\0';
  if (ImGui::Combo("colour", &modeIndex, names.c_str()) && modes[size_t(modeIndex)] != mode) {
    mode = modes[size_t(modeIndex)];
    // Colours are baked on upload: start the residency again with the new mode.
    streamer.reset();
    store.setColourMode(mode);
    streamer = std::make_unique<streaming::Streamer>(reader, store, budgets);
  }
  colourLegend(mode, reader.metadata());
  if (settings.rasteriser == Rasteriser::Points) {
    int splat = settings.splatting == Splatting::Hqs ? 0 : 1;
    if (ImGui::Combo("splatting", &splat, "high quality (blended)\0basic (nearest)\0"))
      settings.splatting = splat == 0 ? Splatting::Hqs : Splatting::Basic;
  }
  ImGui::SliderFloat("point size", &settings.sizeScale, 0.25f, 4.f);
  ImGui::SliderFloat("EDL strength", &settings.edlStrength, 0.f, 5.f);
  ImGui::SliderFloat("EDL radius", &settings.edlRadius, 0.5f, 4.f);
  float pts = float(budgets.points) / 1e6f, gpuMiB = float(budgets.gpuBytes >> 20);
  float spacing = float(budgets.spacingPixels);
  bool changed =
      ImGui::SliderFloat("points (M)", &pts, 0.1f, 50.f, "%.1f", ImGuiSliderFlags_Logarithmic);
  changed |=
      ImGui::SliderFloat("GPU (MiB)", &gpuMiB, 16.f, 8192.f, "%.0f", ImGuiSliderFlags_Logarithmic);
  changed |= ImGui::SliderFloat("spacing px", &spacing, 0.f, 8.f);
  if (changed) {
    budgets.points = uint64_t(pts * 1e6f);
    budgets.gpuBytes = uint64_t(gpuMiB) << 20;
    budgets.spacingPixels = spacing;
    streamer->setBudgets(budgets);
  }
  ImGui::Separator();
  ImGui::Text("cut %u nodes, %.2f M points%s", st.cutNodes, st.cutPoints / 1e6,
              st.complete ? " (complete)" : "");
  ImGui::Text("drawn %u nodes, %.2f M points", st.drawNodes, st.drawPoints / 1e6);
  ImGui::Text("resident %u nodes, %.1f MiB", st.residentNodes, st.residentBytes / 1048576.0);
  ImGui::Text("queue %u, loading %u, uploads %u, evictions %u", st.queueLength, st.inFlight,
              st.uploads, st.evictions);
  ImGui::Text("ms: cut %.2f upload %.2f draw %.1f", st.msCutSelection, st.msUpload, timings.msDraw);
}

gi::SceneCamera sceneCamera(const Camera& cam, int width, int height, double time) {
  gi::SceneCamera c;
  c.eye = cam.eye, c.target = cam.target, c.up = cam.up;
  c.fovYDegrees = cam.fovYDegrees, c.width = width, c.height = height;
  c.time = time;
  return c;
}

// Where the panel's state (position, size, collapsed) is kept between runs: Dear ImGui's ini
// file under $XDG_CONFIG_HOME/nestlight, else ~/.config/nestlight (the XDG base directories);
// empty, and nothing kept, when neither is set or the folder cannot be made.
std::string panelStateFile() {
  std::filesystem::path dir;
  if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg && *xdg)
    dir = xdg;
  else if (const char* home = std::getenv("HOME"); home && *home)
    dir = std::filesystem::path(home) / ".config";
  else
    return "";
  dir /= "nestlight";
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  return ec ? "" : (dir / "imgui.ini").string();
}

// Dear ImGui for the window, shut down before the window's context goes (which writes the
// panel's state file).
struct ImGuiSession {
  explicit ImGuiSession(GLFWwindow* window) : iniFile(panelStateFile()) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = iniFile.empty() ? nullptr : iniFile.c_str();
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
  }
  ~ImGuiSession() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  ImGuiSession(const ImGuiSession&) = delete;
  ImGuiSession& operator=(const ImGuiSession&) = delete;
  const std::string iniFile;
};

std::string timedScreenshotName() {
  char buf[64];
  std::snprintf(buf, sizeof buf, "nestlight-%ld.png", long(std::time(nullptr)));
  return buf;
}

// What the window shows: the scan (when there is one, its colourings) or the scene's meshes alone,
// their bounds and the title.
struct ViewInput {
  std::unique_ptr<OctreeReader> reader;
  ScanColours colours;
  Box3d bounds;
  double extent = 0;
  std::string title;
};

ViewInput openViewInput(const ViewerOptions& opt) {
  ViewInput in;
  // A scene may hold meshes alone: then there is no scan to stream, and the GI frame is the view.
  if (!opt.octree.empty())
    in.reader = std::make_unique<OctreeReader>(opt.octree);  // a bad octree fails before a window
  else if (!opt.scene || opt.scene->meshes.empty())
    throw Error(opt.scene ? opt.scene->file.string() : "", "",
                "nothing to view: no scan and no mesh");
  const Metadata* meta = in.reader ? &in.reader->metadata() : nullptr;
  if (meta) in.colours = scanColours(opt, *meta);
  in.bounds = meta ? meta->bounds : meshBounds(*opt.scene);
  if (in.bounds.empty())
    throw Error(opt.scene->file.string(), "scene.meshes", "the meshes have no finite vertex");
  const Box3d& b = in.bounds;
  in.extent = meta ? meta->cubeWorldSize()
                   : std::max({b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z});
  in.title = in.reader ? opt.octree.filename().string() : opt.scene->file.filename().string();
  return in;
}

// The window's state and its frame: the point view, the GI method the panel chose (MethodView),
// the camera, the panel.
class Viewer {
 public:
  Viewer(const ViewerOptions& opt, ViewInput& in, gl::WindowContext& ctx)
      : opt_(opt), in_(in), ctx_(ctx), settings_(opt.settings), budgets_(opt.budgets) {
    const std::unique_ptr<OctreeReader>& reader = in.reader;
    if (reader) {
      store_ = std::make_unique<frame::GlNodeStore>(reader->metadata(), in.colours.mode,
                                                    in.colours.hdrLayer);
      streamer_ = std::make_unique<streaming::Streamer>(*reader, *store_, budgets_);
      tools_ = std::make_unique<HeritageTools>(opt, *reader);
      if (!opt.tool.empty()) tools_->setTool(opt.tool);
    }
    int w = opt.width, h = opt.height;
    glfwGetFramebufferSize(ctx.window(), &w, &h);
    cc_.from(opt.camera ? *opt.camera
                        : Camera::framing(in.bounds, opt.fovYDegrees,
                                          double(std::max(w, 1)) / std::max(h, 1), opt.azimuth,
                                          opt.elevation));
    cc_.speed = std::max(in.extent * 0.1, 1e-3);
    lastFbo_ = gl::Framebuffer::create();
    if (opt.scene) {
      methods_ = std::make_unique<MethodView>(
          opt.scene, [this](const std::string& status, double f) { redraw(status, f); });
      showMethod_ = !opt.startWithPoints || !reader;
      if (showMethod_) methods_->build();
    }
  }
  ~Viewer() {
    streamer_.reset();
    methods_.reset();  // its GL objects go while the context lives
  }
  // One frame; false once the window is to close or the scripted frames are done.
  bool step();

 private:
  void panel(const streaming::FrameStats& st, const DrawTimings& timings, const Camera& cam,
             bool& shot);
  // Clicks with the tools (the mouse, or the scripted ones), Enter and Ctrl+S, after the points
  // were drawn (picking reads their depth).
  void useTools(const Camera& cam, int fbw, int fbh, const streaming::FrameStats& st);
  void saveView(const Camera& cam, const std::string& file);
  void viewChoice();
  // While a method builds: the last frame and the panel with what it is doing, at most 20 times
  // a second (each costs a frame's swap).
  void redraw(const std::string& status, double fraction);
  void keepLastFrame(int fbw, int fbh);
  void screenshot(const std::string& file, const gi::SceneCamera& sceneCam, const Camera& cam,
                  int fbw, int fbh, uint64_t drawPoints);

  const ViewerOptions& opt_;
  ViewInput& in_;
  gl::WindowContext& ctx_;
  RenderSettings settings_;
  streaming::Budgets budgets_;
  std::unique_ptr<frame::GlNodeStore> store_;
  std::unique_ptr<streaming::Streamer> streamer_;
  PointView renderer_;
  std::unique_ptr<MethodView> methods_;
  std::unique_ptr<HeritageTools> tools_;
  size_t nextClick_ = 0;                // the scripted clicks done
  bool saveHeld_ = false;               // Ctrl+S was down last frame (one save per press)
  double pressX_ = NAN, pressY_ = NAN;  // where the left button went down
  bool showMethod_ = false;
  CameraController cc_;
  std::string status_;
  int frame_ = 0;
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now(), opened_ = last_,
                                        lastRedraw_{};
  double lastX_ = NAN, lastY_ = NAN;
  gl::Framebuffer lastFbo_;
  gl::Texture lastFrame_;
};

void Viewer::keepLastFrame(int fbw, int fbh) {
  if (lastFrame_.width() != fbw || lastFrame_.height() != fbh) {
    lastFrame_ = gl::Texture(GL_RGBA8, fbw, fbh);
    lastFbo_.attach(GL_COLOR_ATTACHMENT0, lastFrame_);
  }
  glBlitNamedFramebuffer(0, lastFbo_.id(), 0, 0, fbw, fbh, 0, 0, fbw, fbh, GL_COLOR_BUFFER_BIT,
                         GL_NEAREST);
}

void Viewer::redraw(const std::string& status, double fraction) {
  const auto now = std::chrono::steady_clock::now();
  if (fraction > 0 && fraction < 1 && now - lastRedraw_ < std::chrono::milliseconds(50)) return;
  lastRedraw_ = now;
  std::printf("view: %s\n", status.c_str());
  std::fflush(stdout);
  glfwPollEvents();
  int fbw = 0, fbh = 0;
  glfwGetFramebufferSize(ctx_.window(), &fbw, &fbh);
  if (fbw <= 0 || fbh <= 0) return;
  const float black[4] = {0, 0, 0, 1};
  glClearNamedFramebufferfv(0, GL_COLOR, 0, black);
  if (lastFrame_.id())
    glBlitNamedFramebuffer(lastFbo_.id(), 0, 0, 0, lastFrame_.width(), lastFrame_.height(), 0, 0,
                           fbw, fbh, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::Begin("nestlight");
  ImGui::TextUnformatted(in_.title.c_str());
  ImGui::PushTextWrapPos(0);
  ImGui::TextUnformatted(status.c_str());
  ImGui::PopTextWrapPos();
  ImGui::ProgressBar(float(std::clamp(fraction, 0.0, 1.0)));
  ImGui::End();
  ImGui::Render();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, fbw, fbh);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  glfwSwapBuffers(ctx_.window());
}

// The view menu: the points (when there is a scan) and every registered method.
void Viewer::viewChoice() {
  if (!methods_) return;
  std::vector<std::string> names;
  if (in_.reader) names.push_back("points");
  for (const std::string& m : gi::registeredMethodNames()) names.push_back(m);
  const std::string shown = showMethod_ ? methods_->methodName() : "points";
  int index = int(std::find(names.begin(), names.end(), shown) - names.begin());
  std::string items;
  for (const auto& n : names) items += n + '\0';
  if (!ImGui::Combo("view", &index, items.c_str())) return;
  const std::string& chosen = names[size_t(index)];
  showMethod_ = chosen != "points";
  // A method is made the first time it is shown (MethodView starts with its build pending).
  if (showMethod_) methods_->select(chosen);
}

void Viewer::saveView(const Camera& cam, const std::string& file) {
  frame::ViewState state = tools_->state(cam, in_.colours.mode, budgets_, settings_);
  // A scene's view: the method and parameters the panel shows (render --state renders them).
  if (methods_) {
    state.gi = {{"method", methods_->methodName()}};
    const nlohmann::json& p = methods_->settings().parameters;
    if (p.is_object() && !p.empty()) state.gi["parameters"] = p;
  }
  tools_->save(file, state);
}

void Viewer::useTools(const Camera& cam, int fbw, int fbh, const streaming::FrameStats& st) {
  GLFWwindow* w = ctx_.window();
  const ImGuiIO& io = ImGui::GetIO();
  tools_->refine(streamer_->drawList(), settings_);
  // A click is a press and a release within 3 pixels (a drag turns the camera instead).
  double x = 0, y = 0;
  glfwGetCursorPos(w, &x, &y);
  const bool down = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  if (down && std::isnan(pressX_) && !io.WantCaptureMouse) pressX_ = x, pressY_ = y;
  if (!down && !std::isnan(pressX_)) {
    if (std::hypot(x - pressX_, y - pressY_) <= 3 && x >= 0 && y >= 0 && x < fbw && y < fbh)
      tools_->click(renderer_, streamer_->drawList(), cam, fbw, fbh, x, y, settings_);
    pressX_ = pressY_ = NAN;
  }
  if (nextClick_ < opt_.clicks.size() && st.complete) {
    const auto& c = opt_.clicks[nextClick_++];
    const bool hit = tools_->click(renderer_, streamer_->drawList(), cam, fbw, fbh, c[0] + 0.5,
                                   c[1] + 0.5, settings_);
    std::printf("view: click %g,%g: %s\n", c[0], c[1], hit ? tools_->status.c_str() : "nothing");
    std::fflush(stdout);
    if (nextClick_ == opt_.clicks.size()) tools_->finish(settings_);
  }
  if (!io.WantCaptureKeyboard) {
    if (glfwGetKey(w, GLFW_KEY_ENTER) == GLFW_PRESS) tools_->finish(settings_);
    const bool ctrl = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                      glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
    const bool save = ctrl && glfwGetKey(w, GLFW_KEY_S) == GLFW_PRESS;
    if (save && !saveHeld_) saveView(cam, tools_->stateFile());
    saveHeld_ = save;
  }
}

void Viewer::panel(const streaming::FrameStats& st, const DrawTimings& timings, const Camera& cam,
                   bool& shot) {
  int fbw = 0, fbh = 0;
  glfwGetFramebufferSize(ctx_.window(), &fbw, &fbh);
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, float(std::min(fbh - 20, 640))), ImGuiCond_FirstUseEver);
  // Collapsed (its title bar's arrow), it keeps to one line; Dear ImGui's state file remembers.
  ImGui::Begin("nestlight");
  // Labels keep 11 characters' room (the longest parameter names wrap no further).
  ImGui::PushItemWidth(-ImGui::GetFontSize() * 11);
  ImGui::TextUnformatted(in_.title.c_str());
  viewChoice();
  shot = ImGui::Button("screenshot");
  if (!status_.empty()) {
    ImGui::SameLine();
    ImGui::TextUnformatted(status_.c_str());
  }
  const bool method = methods_ && showMethod_;
  ImGui::SliderFloat("exposure (stops)", method ? &methods_->exposure() : &settings_.exposureStops,
                     -12.f, 12.f);
  int camMode = cc_.mode == CameraController::Mode::Orbit ? 0 : 1;
  if (ImGui::Combo("camera", &camMode, "orbit (drag, wheel)\0fly (WASD QE, drag)\0"))
    cc_.mode = camMode == 0 ? CameraController::Mode::Orbit : CameraController::Mode::Fly;
  ImGui::Separator();
  if (method)
    methods_->panel();
  else if (in_.reader) {
    pointsPanel(settings_, in_.colours, *in_.reader, *store_, streamer_, budgets_, st, timings);
    ImGui::Separator();
    tools_->panel(settings_, cam, in_.extent);
    if (ImGui::Button("save view (Ctrl+S)")) saveView(cam, tools_->stateFile());
    ImGui::SameLine();
    ImGui::TextDisabled("%s", tools_->stateFile().c_str());
  }
  ImGui::PopItemWidth();
  ImGui::End();
}

void Viewer::screenshot(const std::string& file, const gi::SceneCamera& sceneCam, const Camera& cam,
                        int fbw, int fbh, uint64_t drawPoints) {
  std::string what;
  if (methods_ && showMethod_) {
    what = methods_->screenshot(file, sceneCam);
  } else {
    Image img = renderer_.render(streamer_->drawList(), *store_, cam, fbw, fbh, settings_);
    tools_->drawInto(img, cam);  // the measurements and labels, as the window shows them
    writeImage(img, file);
    what = std::to_string(fbw) + "x" + std::to_string(fbh) + ", " + std::to_string(drawPoints) +
           " points drawn";
  }
  status_ = "saved " + file;
  // The terminal shows the whole path; the panel may cut it.
  std::printf("view: %s (%s)\n", status_.c_str(), what.c_str());
  std::fflush(stdout);
}

bool Viewer::step() {
  GLFWwindow* w = ctx_.window();
  // A progressive view idles between events so that its worker has the cores.
  if (methods_ && showMethod_ && methods_->progressive() && opt_.frames == 0)
    glfwWaitEventsTimeout(1.0 / 30);
  else
    glfwPollEvents();
  if (glfwWindowShouldClose(w)) return false;
  const auto now = std::chrono::steady_clock::now();
  const double dt = std::chrono::duration<double>(now - last_).count();
  last_ = now;
  double x = 0, y = 0;
  glfwGetCursorPos(w, &x, &y);
  if (!std::isnan(lastX_)) moveCamera(cc_, w, ImGui::GetIO(), x - lastX_, y - lastY_, dt);
  lastX_ = x, lastY_ = y;
  cc_.yaw += opt_.orbitDegreesPerFrame;
  int fbw = 0, fbh = 0;
  glfwGetFramebufferSize(w, &fbw, &fbh);
  if (fbw <= 0 || fbh <= 0) return true;  // minimised
  Camera cam = cc_.camera();
  cam.fitClipPlanes(in_.bounds);
  // Near the scan, near/far from the box alone would clip what is in front of the eye.
  cam.nearPlane = std::max(std::min(cam.nearPlane, cc_.distance * 0.01), cam.farPlane * 1e-5);
  const gi::SceneCamera sceneCam =
      sceneCamera(cam, fbw, fbh, std::chrono::duration<double>(now - opened_).count());
  streaming::FrameStats st{};
  if (streamer_) {
    streaming::View view = cam.view(fbw, fbh);
    view.clip = settings_.clip.get();  // what the volumes remove whole is never loaded
    st = streamer_->update(view);
  }
  DrawTimings timings;
  if (methods_) methods_->setShown(showMethod_);
  if (methods_ && showMethod_) {
    methods_->draw(sceneCam, fbw, fbh);
  } else {
    renderer_.renderToTexture(streamer_->drawList(), *store_, cam, fbw, fbh, settings_, &timings);
    glBlitNamedFramebuffer(renderer_.outputFramebuffer(), 0, 0, 0, fbw, fbh, 0, 0, fbw, fbh,
                           GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  bool shot = false;
  // Clicks pick from the points' depth; the measurements and labels are drawn over either view
  // (a GI method's frame is rendered from the same camera).
  if (tools_ && !(methods_ && showMethod_)) useTools(cam, fbw, fbh, st);
  if (tools_) tools_->drawOverlay(cam, fbw, fbh);
  panel(st, timings, cam, shot);
  // A method to be made: the frame as it is now (the panel not yet drawn) stays on screen.
  const bool build = methods_ && showMethod_ && methods_->buildPending();
  if (build) keepLastFrame(fbw, fbh);
  ImGui::Render();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, fbw, fbh);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  ++frame_;
  const bool lastFrame = opt_.frames > 0 && frame_ >= opt_.frames;
  if (shot || (lastFrame && !opt_.screenshot.empty())) {
    // A scripted run's progressive view is saved once it holds its samples per pixel.
    if (lastFrame && methods_ && showMethod_ && !methods_->waitForSamples(600))
      std::fprintf(stderr, "view: the samples per pixel were not reached in 600 s\n");
    // The last frame's goes where asked; a button's gets the time in its name.
    screenshot(lastFrame && !opt_.screenshot.empty() ? opt_.screenshot : timedScreenshotName(),
               sceneCam, cam, fbw, fbh, st.drawPoints);
  }
  if (lastFrame && !opt_.saveState.empty() && tools_) saveView(cam, opt_.saveState);
  glfwSwapBuffers(w);
  if (build) methods_->build();
  return !lastFrame;
}

}  // namespace

std::vector<std::string> toolNames() {
  return HeritageTools::toolNames();
}

int runViewer(const ViewerOptions& opt) {
  ViewInput in = openViewInput(opt);
  gl::WindowContext ctx(opt.width, opt.height, "nestlight view - " + in.title);
  std::printf("view: %s\n", ctx.description().c_str());
  const ImGuiSession imgui(ctx.window());
  {
    Viewer viewer(opt, in, ctx);
    while (viewer.step()) {
    }
  }
  return 0;
}

}  // namespace nestlight::viewer
