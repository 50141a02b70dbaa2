#include "method_view.h"

#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::viewer {

namespace {

using json = nlohmann::json;

// The scene's settings for `info`: the parameters it declares are kept (the scene's and the
// command line's), the others dropped (they were written for another method).
gi::GiSettings settingsFor(const gi::Scene& scene, const gi::MethodInfo& info) {
  gi::GiSettings g = scene.gi;
  g.method = info.name;
  json kept = json::object();
  if (g.parameters.is_object())
    for (const auto& p : info.parameters)
      if (g.parameters.contains(p.name)) kept[p.name] = g.parameters[p.name];
  g.parameters = kept;
  return g;
}

bool sameSettings(const gi::GiSettings& a, const gi::GiSettings& b) {
  return a.method == b.method && a.mode == b.mode && a.maxBounces == b.maxBounces &&
         a.samplesPerPixel == b.samplesPerPixel && a.seed == b.seed && a.parameters == b.parameters;
}

// The variant whose settings these are (applying it changes nothing), for the panel's first
// frame: `view --variant classic` shows pbgi's "classic" chosen.
int matchingVariant(const gi::MethodInfo& info, const gi::GiSettings& g) {
  for (size_t i = 0; i < info.variants.size(); ++i) {
    gi::GiSettings v = g;
    info.variants[i].apply(v);
    if (sameSettings(v, g)) return int(i);
  }
  return -1;
}

enum class Edit { None, Changed, Committed };

// An integer parameter: a checkbox for its word ("auto") or for the method's own default (a null
// default), else a slider over a short range, a list of powers of two, or a number field.
Edit integerWidget(const gi::ParameterSpec& p, json& v) {
  Edit e = Edit::None;
  if (!p.choices.empty() || p.defaultValue.is_null()) {
    bool automatic = !v.is_number();
    const std::string word = p.choices.empty() ? "the method's" : p.choices.front();
    if (ImGui::Checkbox(("##" + p.name).c_str(), &automatic)) {
      const json number = p.defaultValue.is_number() ? p.defaultValue : json(int64_t(p.min));
      v = automatic ? (p.choices.empty() ? json() : json(word)) : number;
      return Edit::Committed;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", word.c_str());
    ImGui::SameLine();
    if (automatic) {
      ImGui::Text("%s: %s", p.name.c_str(), word.c_str());
      return e;
    }
  }
  int64_t n = v.get<int64_t>();
  const int64_t lo = int64_t(p.min), hi = int64_t(p.max);
  if (p.powerOfTwo) {
    std::string items;
    int index = 0, count = 0;
    for (int64_t q = std::max<int64_t>(lo, 1); q <= hi; q *= 2, ++count) {
      items += std::to_string(q) + '\0';
      if (q == n) index = count;
    }
    if (ImGui::Combo(p.name.c_str(), &index, items.c_str())) {
      v = std::max<int64_t>(lo, 1) << index;
      e = Edit::Committed;
    }
  } else if (hi - lo <= 4096) {
    int x = int(n);
    if (ImGui::SliderInt(p.name.c_str(), &x, int(lo), int(hi))) v = x, e = Edit::Changed;
  } else {
    if (ImGui::InputScalar(p.name.c_str(), ImGuiDataType_S64, &n)) {
      v = std::clamp(n, lo, hi);
      e = Edit::Changed;
    }
  }
  return e;
}

Edit numberWidget(const gi::ParameterSpec& p, json& v) {
  double x = v.is_number() ? v.get<double>() : 0.0;
  bool changed;
  if (std::isfinite(p.min) && std::isfinite(p.max)) {
    // Ranges over orders of magnitude (budgets, ratios) on a logarithmic scale.
    const ImGuiSliderFlags log =
        p.min > 0 && p.max / p.min >= 100 ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None;
    changed = ImGui::SliderScalar(p.name.c_str(), ImGuiDataType_Double, &x, &p.min, &p.max, "%.4g",
                                  log | ImGuiSliderFlags_AlwaysClamp);
  } else {
    changed = ImGui::InputDouble(p.name.c_str(), &x, 0, 0, "%.4g");
  }
  if (changed) v = std::clamp(x, p.min, p.max);
  return changed ? Edit::Changed : Edit::None;
}

// One declared parameter's widget. Changed: the value moves (a slider held); Committed: the
// method is to be made again (a slider let go, a box ticked, a choice made).
Edit parameterWidget(const gi::ParameterSpec& p, json& v) {
  ImGui::PushID(p.name.c_str());
  Edit e = Edit::None;
  switch (p.type) {
    case gi::ParameterType::Boolean: {
      bool b = v.is_boolean() && v.get<bool>();
      if (ImGui::Checkbox(p.name.c_str(), &b)) v = b, e = Edit::Committed;
      break;
    }
    case gi::ParameterType::Choice: {
      const std::string now = v.is_string() ? v.get<std::string>() : "";
      int index = 0;
      std::string items;
      for (size_t i = 0; i < p.choices.size(); ++i) {
        items += p.choices[i] + '\0';
        if (p.choices[i] == now) index = int(i);
      }
      if (ImGui::Combo(p.name.c_str(), &index, items.c_str()))
        v = p.choices[size_t(index)], e = Edit::Committed;
      break;
    }
    case gi::ParameterType::String: {
      char buffer[512];
      std::snprintf(buffer, sizeof buffer, "%s", v.is_string() ? v.get<std::string>().c_str() : "");
      if (ImGui::InputText(p.name.c_str(), buffer, sizeof buffer)) v = buffer, e = Edit::Changed;
      break;
    }
    case gi::ParameterType::Integer:
      e = integerWidget(p, v);
      break;
    case gi::ParameterType::Number:
      e = numberWidget(p, v);
      break;
    case gi::ParameterType::Pixels:  // set in the scene file; shown, not edited
      ImGui::TextUnformatted((p.name + ": " + v.dump()).c_str());
      break;
  }
  if (e != Edit::Committed && ImGui::IsItemDeactivatedAfterEdit()) e = Edit::Committed;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("%s\n%s, default %s", p.help.c_str(), gi::describeParameterType(p).c_str(),
                      p.defaultValue.is_null() ? "the method's" : p.defaultValue.dump().c_str());
  ImGui::PopID();
  return e;
}

}  // namespace

MethodView::MethodView(std::shared_ptr<const gi::Scene> scene, Redraw redraw)
    : scene_(std::move(scene)), redraw_(std::move(redraw)) {
  const gi::MethodInfo& info = *gi::findMethod(scene_->gi.method);
  settings_ = settingsFor(*scene_, info);
  lastGood_ = settings_;
  variant_ = matchingVariant(info, settings_);
  exposure_ = float(scene_->output.exposure);
  readFbo_ = gl::Framebuffer::create();
}

MethodView::~MethodView() = default;

void MethodView::select(const std::string& method) {
  const gi::MethodInfo* info = gi::findMethod(method);
  if (!info || method == settings_.method) return;
  settings_ = settingsFor(*scene_, *info);
  variant_ = matchingVariant(*info, settings_);
  pending_ = true;
}

void MethodView::build() {
  pending_ = false;
  const gi::MethodInfo& info = *gi::findMethod(settings_.method);
  const std::string name = settings_.method;
  // The old method goes first: two GL methods' resident cuts need not fit at once.
  progressive_.reset();
  method_.reset();
  stats_ = {};
  shownVersion_ = ~0ull;
  shown_ = {};
  gi::Scene scene = *scene_;
  scene.gi = settings_;
  redraw_("building " + name + "...", 0);
  try {
    if (info.gpu) {
      gi::MethodContext mc(false, true);
      mc.progress = [&](const std::string& stage, double f) {
        redraw_("building " + name + ": " + stage, f);
      };
      method_ = gi::createMethod(scene, mc);
      firstFrame_ = true;
      std::printf("view: %s through the GI frame\n", name.c_str());
    } else {
      std::unique_ptr<gi::Method> m = gi::createMethod(scene, gi::MethodContext(false, false));
      if (!m->rendersInBatches())
        throw Error(scene.file.string(), "scene.gi.method",
                    name + " renders neither in real time nor in batches: `nestlight render` it");
      progressive_ = std::make_unique<ProgressiveView>(std::move(m), settings_.samplesPerPixel);
      progressive_->setDivisor(divisorChoice_);
      std::printf("view: %s progressively, up to %d samples per pixel\n", name.c_str(),
                  settings_.samplesPerPixel);
    }
    std::fflush(stdout);
    error_.clear();
    lastGood_ = settings_;
  } catch (const std::exception& e) {
    error_ = e.what();
    std::fprintf(stderr, "view: %s\n", error_.c_str());
    if (!sameSettings(settings_, lastGood_)) {
      const std::string failed = error_;
      settings_ = lastGood_;
      variant_ = matchingVariant(*gi::findMethod(settings_.method), settings_);
      build();
      error_ = failed;  // shown until the next change
    }
  }
}

void MethodView::draw(const gi::SceneCamera& camera, int fbw, int fbh) {
  const float black[4] = {0, 0, 0, 1};
  if (method_) {
    if (firstFrame_) redraw_(settings_.method + ": rendering the first frame", 1.0);
    firstFrame_ = false;
    GLuint tex = 0;
    try {
      tex = method_->renderInteractive(camera, exposure_, &stats_);
    } catch (const std::exception& e) {
      error_ = e.what();
      std::fprintf(stderr, "view: %s\n", error_.c_str());
      method_.reset();
    }
    if (tex) {
      readFbo_.attachRaw(GL_COLOR_ATTACHMENT0, tex);
      glBlitNamedFramebuffer(readFbo_.id(), 0, 0, 0, fbw, fbh, 0, 0, fbw, fbh, GL_COLOR_BUFFER_BIT,
                             GL_NEAREST);
      return;
    }
  } else if (progressive_) {
    progressive_->setCamera(camera);
    drawProgressive(fbw, fbh);
    return;
  }
  glClearNamedFramebufferfv(0, GL_COLOR, 0, black);
}

// The running mean, tone-mapped when it or the exposure changed, stretched over the window (top
// row first, as the path tracer writes it).
void MethodView::drawProgressive(int fbw, int fbh) {
  const uint64_t version = progressive_->version();
  if (version != shownVersion_ || exposure_ != shownExposure_) {
    if (version != shownVersion_) shown_ = progressive_->snapshot();
    shownVersion_ = version;
    shownExposure_ = exposure_;
    const gi::HdrImage& mean = shown_.mean;
    if (!mean.rgb.empty()) {
      if (progressiveTexture_.width() != mean.width || progressiveTexture_.height() != mean.height)
        progressiveTexture_ = gl::Texture(GL_RGBA8, mean.width, mean.height);
      const gi::HdrImage display = gi::toneMap(mean, exposure_);
      std::vector<uint8_t> bytes(mean.pixels() * 4, 255);
      for (size_t i = 0; i < mean.pixels(); ++i)
        for (int c = 0; c < 3; ++c) {
          const float d = display.rgb[3 * i + c];
          bytes[4 * i + c] = uint8_t(std::isfinite(d) ? std::clamp(d, 0.f, 1.f) * 255.f + 0.5f : 0);
        }
      glTextureSubImage2D(progressiveTexture_.id(), 0, 0, 0, mean.width, mean.height, GL_RGBA,
                          GL_UNSIGNED_BYTE, bytes.data());
    }
  }
  if (!progressiveTexture_.id()) {
    const float black[4] = {0, 0, 0, 1};
    glClearNamedFramebufferfv(0, GL_COLOR, 0, black);
    return;
  }
  readFbo_.attach(GL_COLOR_ATTACHMENT0, progressiveTexture_);
  const int w = progressiveTexture_.width(), h = progressiveTexture_.height();
  glBlitNamedFramebuffer(readFbo_.id(), 0, 0, 0, w, h, 0, fbh, fbw, 0, GL_COLOR_BUFFER_BIT,
                         w == fbw && h == fbh ? GL_NEAREST : GL_LINEAR);
}

bool MethodView::waitForSamples(double timeoutSeconds) const {
  return !progressive_ || progressive_->waitFor(progressive_->maxSamplesPerPixel(), timeoutSeconds);
}

std::string MethodView::screenshot(const std::string& file, const gi::SceneCamera& camera) {
  gi::HdrImage image;
  gi::ImageAttributes attributes;
  char line[256];
  if (method_) {
    gi::MethodFrame f = method_->render(camera);
    image = std::move(f.image);
    attributes = f.attributes;
    std::snprintf(line, sizeof line, "%dx%d, %s", image.width, image.height,
                  settings_.method.c_str());
  } else if (progressive_) {
    const ProgressiveView::Snapshot s = progressive_->snapshot();
    if (s.mean.rgb.empty()) throw Error(file, "", "nothing accumulated yet to save");
    image = s.mean;
    attributes["nestlight:samples"] = std::to_string(s.samplesPerPixel);
    std::snprintf(line, sizeof line, "%dx%d, %s %d samples per pixel in %.2f s", image.width,
                  image.height, settings_.method.c_str(), s.samplesPerPixel, s.seconds);
  } else {
    throw Error(file, "", "no method to save a frame of: " + error_);
  }
  attributes["nestlight:method"] = settings_.method;
  if (std::filesystem::path(file).extension() == ".exr")
    gi::writeExr(file, image, attributes);
  else
    gi::writeToneMappedPng(file, image, exposure_);
  return line;
}

void MethodView::panel() {
  const gi::MethodInfo& info = *gi::findMethod(settings_.method);
  if (!error_.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", error_.c_str());
    ImGui::PopTextWrapPos();
  }
  variantAndSettingsPanel(info);
  parametersPanel(info);
  figuresPanel();
}

void MethodView::variantAndSettingsPanel(const gi::MethodInfo& info) {
  if (!info.variants.empty()) {
    std::string items = std::string("(none)") + '\0';
    for (const auto& v : info.variants) items += v.name + '\0';
    int index = variant_ + 1;
    if (ImGui::Combo("variant", &index, items.c_str()) && index - 1 != variant_) {
      // A variant applies to the scene's settings, not to the panel's edits before it.
      settings_ = settingsFor(*scene_, info);
      variant_ = index - 1;
      if (variant_ >= 0) info.variants[size_t(variant_)].apply(settings_);
      pending_ = true;
    }
  }
  int mode = settings_.mode == gi::RadianceMode::Albedo ? 1 : 0;
  if (ImGui::Combo("mode", &mode, "radiance_cache\0albedo\0")) {
    settings_.mode = mode == 1 ? gi::RadianceMode::Albedo : gi::RadianceMode::RadianceCache;
    pending_ = true;
  }
  ImGui::SliderInt("bounces", &settings_.maxBounces, 0, 16);
  pending_ |= ImGui::IsItemDeactivatedAfterEdit();
  if (info.gpu) return;
  ImGui::InputInt("spp at most", &settings_.samplesPerPixel, 0);
  if (ImGui::IsItemDeactivatedAfterEdit()) {
    settings_.samplesPerPixel = std::clamp(settings_.samplesPerPixel, 1, 1 << 24);
    pending_ = true;
  }
  if (ImGui::Combo("resolution", &divisorChoice_, "auto\0full\0half\0quarter\0eighth\0") &&
      progressive_)
    progressive_->setDivisor(divisorChoice_ == 0 ? 0 : 1 << (divisorChoice_ - 1));
}

void MethodView::parametersPanel(const gi::MethodInfo& info) {
  if (info.parameters.empty()) return;
  if (!ImGui::TreeNode("parameters")) return;
  json& given = settings_.parameters;
  if (!given.is_object()) given = json::object();
  for (const gi::ParameterSpec& p : info.parameters) {
    json v = given.contains(p.name) ? given[p.name] : p.defaultValue;
    const Edit e = parameterWidget(p, v);
    if (e == Edit::None) continue;
    if (v.is_null())
      given.erase(p.name);
    else
      given[p.name] = v;
    pending_ |= e == Edit::Committed;
  }
  ImGui::TreePop();
}

void MethodView::figuresPanel() {
  if (progressive_) {
    const ProgressiveView::Snapshot& s = shown_;
    ImGui::Text("%d spp, %.1f s%s", s.samplesPerPixel, s.seconds, s.complete ? " (done)" : "");
    if (!s.mean.rgb.empty())
      ImGui::Text("%dx%d (1/%d of the window)", s.mean.width, s.mean.height, s.divisor);
    if (!s.error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", s.error.c_str());
    return;
  }
  // A method that refines while the view rests says how far it got.
  if (auto it = stats_.attributes.find("nestlight:progress"); it != stats_.attributes.end())
    ImGui::Text("%s", it->second.c_str());
  double total = 0;
  for (const auto& [name, ms] : stats_.passMs) {
    ImGui::Text("%-16s %7.2f ms", name.c_str(), ms);
    total += ms;
  }
  ImGui::Text("%-16s %7.2f ms (frame %.1f ms)", "GPU total", total, stats_.seconds * 1e3);
}

}  // namespace nestlight::viewer
