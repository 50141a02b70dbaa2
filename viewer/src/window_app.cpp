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
#include <glm/gtc/matrix_transform.hpp>

#include "nestlight/gi/mesh.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/image.h"

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

// The point view's part of the panel: rasteriser, colouring, splatting, budgets and the
// streaming figures. A colouring change restarts the residency (colours are baked on upload).
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
  if (settings.rasteriser == Rasteriser::Points) {
    int splat = settings.splatting == Splatting::Hqs ? 0 : 1;
    if (ImGui::Combo("splatting", &splat, "high quality (blended)\0basic (nearest)\0"))
      settings.splatting = splat == 0 ? Splatting::Hqs : Splatting::Basic;
  }
  ImGui::SliderFloat("exposure (stops)", &settings.exposureStops, -12.f, 4.f);
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

// The GI frame's part of the panel: exposure, the method's parameters and its passes' times.
void methodPanel(const gi::Method& method, float& exposure, const gi::MethodFrame& stats) {
  ImGui::SliderFloat("exposure (EV)", &exposure, -10.f, 10.f);
  if (ImGui::TreeNode("parameters")) {
    // The values as the method resolved them; a declared parameter's help is its tooltip.
    const gi::MethodInfo* info = gi::findMethod(method.name());
    for (const auto& [k, v] : method.parameters()) {
      ImGui::Text("%s = %s", k.c_str(), v.c_str());
      if (!info || !ImGui::IsItemHovered()) continue;
      for (const auto& p : info->parameters)
        if (p.name == k)
          ImGui::SetTooltip(
              "%s\n%s, default %s", p.help.c_str(), gi::describeParameterType(p).c_str(),
              p.defaultValue.is_null() ? "the method's" : p.defaultValue.dump().c_str());
    }
    ImGui::TreePop();
  }
  double total = 0;
  for (const auto& [name, ms] : stats.passMs) {
    ImGui::Text("%-16s %7.2f ms", name.c_str(), ms);
    total += ms;
  }
  ImGui::Text("%-16s %7.2f ms (frame %.1f ms)", "GPU total", total, stats.seconds * 1e3);
  ImGui::Separator();
}

// The view as shown, saved: the method's linear frame (EXR as rendered, PNG through the panel's
// exposure) or the point view's image.
void saveScreenshot(const std::string& file, gi::Method* method, const gi::SceneCamera& sceneCam,
                    float exposure, PointView& renderer, streaming::Streamer* streamer,
                    frame::GlNodeStore* store, const Camera& cam, int fbw, int fbh,
                    const RenderSettings& settings) {
  if (method) {
    const gi::MethodFrame f = method->render(sceneCam);
    if (std::filesystem::path(file).extension() == ".exr")
      gi::writeExr(file, f.image, f.attributes);
    else
      gi::writeToneMappedPng(file, f.image, exposure);
  } else {
    Image img = renderer.render(streamer->drawList(), *store, cam, fbw, fbh, settings);
    writeImage(img, file);
  }
}

// The scene's GI method for the window: one that renders offline is replaced by raster, and
// `note` says so.
std::unique_ptr<gi::Method> interactiveMethod(gi::Scene s, std::string& note) {
  const gi::MethodInfo* info = gi::findMethod(s.gi.method);
  if (!info || !info->gpu) {
    note = s.gi.method + " renders offline (nestlight render); shown: raster";
    s.gi.method = "raster";
  }
  return gi::createMethod(s, {false, true});
}

gi::SceneCamera sceneCamera(const Camera& cam, int width, int height, double time) {
  gi::SceneCamera c;
  c.eye = cam.eye, c.target = cam.target, c.up = cam.up;
  c.fovYDegrees = cam.fovYDegrees, c.width = width, c.height = height;
  c.time = time;
  return c;
}

// Dear ImGui for the window, shut down before the window's context goes.
struct ImGuiSession {
  explicit ImGuiSession(GLFWwindow* window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
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

}  // namespace

int runViewer(const ViewerOptions& opt) {
  ViewInput in = openViewInput(opt);
  const std::unique_ptr<OctreeReader>& reader = in.reader;
  const Metadata* meta = reader ? &reader->metadata() : nullptr;
  ScanColours& colours = in.colours;
  const frame::ColourMode& mode = colours.mode;
  const std::shared_ptr<const ColourLayerReader>& hdrLayer = colours.hdrLayer;
  const Box3d& bounds = in.bounds;
  const double extent = in.extent;
  const std::string& title = in.title;
  gl::WindowContext ctx(opt.width, opt.height, "nestlight view - " + title);
  std::printf("view: %s\n", ctx.description().c_str());

  const ImGuiSession imgui(ctx.window());

  int exitCode = 0;
  {
    // The scene's GI method, when the viewer was given a scene: made here, in the window's context.
    std::unique_ptr<gi::Method> method;
    std::string methodNote;
    gl::Framebuffer methodFbo;
    bool showMethod = false;
    float exposure = opt.scene ? float(opt.scene->output.exposure) : 0.0f;
    gi::MethodFrame methodStats;
    if (opt.scene) {
      method = interactiveMethod(*opt.scene, methodNote);
      methodFbo = gl::Framebuffer::create();
      showMethod = !opt.startWithPoints || !reader;
      std::printf("view: %s through the GI frame%s\n", method->name().c_str(),
                  methodNote.empty() ? "" : (" (" + methodNote + ")").c_str());
    }
    std::unique_ptr<frame::GlNodeStore> store;
    std::unique_ptr<streaming::Streamer> streamer;
    PointView renderer;
    RenderSettings settings = opt.settings;
    streaming::Budgets budgets = opt.budgets;
    if (reader) {
      store = std::make_unique<frame::GlNodeStore>(*meta, mode, hdrLayer);
      streamer = std::make_unique<streaming::Streamer>(*reader, *store, budgets);
    }
    CameraController cc;
    int winW = opt.width, winH = opt.height;
    glfwGetFramebufferSize(ctx.window(), &winW, &winH);
    cc.from(opt.camera ? *opt.camera
                       : Camera::framing(bounds, opt.fovYDegrees,
                                         double(std::max(winW, 1)) / std::max(winH, 1), opt.azimuth,
                                         opt.elevation));
    cc.speed = std::max(extent * 0.1, 1e-3);
    std::string status;
    int frame = 0;
    auto last = std::chrono::steady_clock::now();
    const auto opened = last;  // a scene's video light probe plays from here
    double lastX = 0, lastY = 0;
    glfwGetCursorPos(ctx.window(), &lastX, &lastY);
    std::vector<float> pointMillions{float(budgets.points) / 1e6f};
    while (!glfwWindowShouldClose(ctx.window())) {
      glfwPollEvents();
      const auto now = std::chrono::steady_clock::now();
      const double dt = std::chrono::duration<double>(now - last).count();
      last = now;
      ImGuiIO& io = ImGui::GetIO();

      // Camera input, unless the panel has the mouse or keyboard.
      double x = 0, y = 0;
      glfwGetCursorPos(ctx.window(), &x, &y);
      const double dx = x - lastX, dy = y - lastY;
      lastX = x, lastY = y;
      GLFWwindow* w = ctx.window();
      moveCamera(cc, w, io, dx, dy, dt);
      cc.yaw += opt.orbitDegreesPerFrame;

      int fbw = 0, fbh = 0;
      glfwGetFramebufferSize(w, &fbw, &fbh);
      if (fbw <= 0 || fbh <= 0) continue;  // minimised
      Camera cam = cc.camera();
      cam.fitClipPlanes(bounds);
      // Near the scan, near/far from the box alone would clip what is in front of the eye.
      cam.nearPlane = std::max(std::min(cam.nearPlane, cc.distance * 0.01), cam.farPlane * 1e-5);
      const gi::SceneCamera sceneCam =
          sceneCamera(cam, fbw, fbh, std::chrono::duration<double>(now - opened).count());
      streaming::FrameStats st{};
      if (streamer) st = streamer->update(cam.view(fbw, fbh));
      DrawTimings timings;
      if (showMethod) {
        const GLuint tex = method->renderInteractive(sceneCam, exposure, &methodStats);
        methodFbo.attachRaw(GL_COLOR_ATTACHMENT0, tex);
        glBlitNamedFramebuffer(methodFbo.id(), 0, 0, 0, fbw, fbh, 0, 0, fbw, fbh,
                               GL_COLOR_BUFFER_BIT, GL_NEAREST);
      } else {
        renderer.renderToTexture(streamer->drawList(), *store, cam, fbw, fbh, settings, &timings);
        glBlitNamedFramebuffer(renderer.outputFramebuffer(), 0, 0, 0, fbw, fbh, 0, 0, fbw, fbh,
                               GL_COLOR_BUFFER_BIT, GL_NEAREST);
      }

      // The panel.
      ImGui_ImplOpenGL3_NewFrame();
      ImGui_ImplGlfw_NewFrame();
      ImGui::NewFrame();
      ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
      ImGui::Begin("nestlight");
      ImGui::Text("%s", title.c_str());
      if (method && !reader) {
        ImGui::Text("%s (GI frame; the scene has no scan)", method->name().c_str());
      } else if (method) {
        int view = showMethod ? 0 : 1;
        const std::string views = method->name() + " (GI frame)" + '\0' + "points" + '\0';
        if (ImGui::Combo("view", &view, views.c_str())) showMethod = view == 0;
      }
      if (method && !methodNote.empty()) ImGui::TextUnformatted(methodNote.c_str());
      if (method && (showMethod || !reader)) methodPanel(*method, exposure, methodStats);
      int camMode = cc.mode == CameraController::Mode::Orbit ? 0 : 1;
      if (ImGui::Combo("camera", &camMode, "orbit (drag, wheel)\0fly (WASD QE, drag)\0"))
        cc.mode = camMode == 0 ? CameraController::Mode::Orbit : CameraController::Mode::Fly;
      if (reader) pointsPanel(settings, colours, *reader, *store, streamer, budgets, st, timings);
      bool shot = ImGui::Button("screenshot");
      if (!status.empty()) ImGui::TextUnformatted(status.c_str());
      ImGui::End();
      ImGui::Render();
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      glViewport(0, 0, fbw, fbh);
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());

      ++frame;
      const bool last = opt.frames > 0 && frame >= opt.frames;
      if (shot || (last && !opt.screenshot.empty())) {
        // The last frame's goes where asked; a button's gets the time in its name.
        const std::string file =
            last && !opt.screenshot.empty() ? opt.screenshot : timedScreenshotName();
        saveScreenshot(file, showMethod ? method.get() : nullptr, sceneCam, exposure, renderer,
                       streamer.get(), store.get(), cam, fbw, fbh, settings);
        status = "saved " + file;
        std::printf("view: %s (%dx%d, %llu points drawn)\n", status.c_str(), fbw, fbh,
                    (unsigned long long)st.drawPoints);
      }
      glfwSwapBuffers(w);
      if (last) break;
    }
    streamer.reset();
    method.reset();  // its GL objects go while the context lives
  }
  return exitCode;
}

}  // namespace nestlight::viewer
