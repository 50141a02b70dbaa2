// The window's GI side (viewer-internal): the method the panel or the command line chose, made
// from the registry with its variant and parameters; a GL method renders each frame in the
// window's context, a method that samples (the path tracer) accumulates progressively on a worker
// thread (nestlight/viewer/progressive.h). Its panel lists every registered method, variant and
// declared parameter (gi::MethodInfo), and a change re-creates the method.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gl/resources.h"
#include "nestlight/viewer/progressive.h"

namespace nestlight::viewer {

class MethodView {
 public:
  // While a method builds: draw the last frame and the panel with `status` and `fraction`.
  using Redraw = std::function<void(const std::string& status, double fraction)>;
  MethodView(std::shared_ptr<const gi::Scene> scene, Redraw redraw);
  ~MethodView();
  MethodView(const MethodView&) = delete;
  MethodView& operator=(const MethodView&) = delete;

  // Chooses a registered method: its own parameters from the scene (and the command line) are
  // kept, others dropped; it is made at the next build().
  void select(const std::string& method);
  // Makes the chosen method with the chosen settings (outside an ImGui frame: it redraws). On
  // failure the error is shown and the last method that worked is made again.
  void build();
  bool buildPending() const { return pending_; }
  const std::string& methodName() const { return settings_.method; }
  // The chosen method's settings (its parameters as the panel set them).
  const gi::GiSettings& settings() const { return settings_; }
  bool progressive() const { return progressive_ != nullptr; }
  // Whether the window shows the method: a progressive view shown no more stops sampling.
  void setShown(bool shown) {
    if (progressive_) progressive_->setPaused(!shown);
  }

  // Draws the view into the window (framebuffer 0) at fbw x fbh.
  void draw(const gi::SceneCamera& camera, int fbw, int fbh);
  // The panel's method part: variant, mode, bounces, the declared parameters, the figures.
  void panel();
  float& exposure() { return exposure_; }
  // Scripted runs: waits until a progressive view holds its samples per pixel (true when it does
  // or the method is not progressive).
  bool waitForSamples(double timeoutSeconds) const;
  // The view as shown: the GL method's linear frame, or the progressive mean (EXR linear, PNG
  // through the exposure). Returns a line for the log.
  std::string screenshot(const std::string& file, const gi::SceneCamera& camera);

 private:
  void variantAndSettingsPanel(const gi::MethodInfo& info);
  void parametersPanel(const gi::MethodInfo& info);
  void figuresPanel();
  void drawProgressive(int fbw, int fbh);

  std::shared_ptr<const gi::Scene> scene_;
  Redraw redraw_;
  gi::GiSettings settings_, lastGood_;
  int variant_ = -1;  // the MethodInfo::variants entry chosen in the panel (-1: none)
  bool pending_ = true;
  bool firstFrame_ = false;
  std::string error_;
  float exposure_ = 0;
  std::unique_ptr<gi::Method> method_;            // GL
  std::unique_ptr<ProgressiveView> progressive_;  // sampling methods
  gi::MethodFrame stats_;
  gl::Framebuffer readFbo_;
  gl::Texture progressiveTexture_;
  uint64_t shownVersion_ = ~0ull;
  float shownExposure_ = NAN;
  ProgressiveView::Snapshot shown_;
  int divisorChoice_ = 0;
};

}  // namespace nestlight::viewer
