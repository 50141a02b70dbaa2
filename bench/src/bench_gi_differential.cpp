// `bench gi`'s ground truth of differential rendering (bench_gi_differential.h).
#include "bench_gi_differential.h"

#include <algorithm>
#include <cmath>

#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench::differential {

namespace fs = std::filesystem;
using gi::HdrImage;

namespace {

HdrImage renderOnce(const gi::Scene& s) {
  return gi::createMethod(s, {true, false, true})->render(s.camera).image;
}

// The scan's colour source shown as radiance: the raster frame in the radiance-cache mode draws
// scan points with their colour and nothing else (no lights, no environment: inserted meshes are
// black and only hide what is behind them, as in the frame diffrender draws).
HdrImage scanColours(gi::Scene s, const std::string& layer, std::optional<float> scale) {
  s.gi.method = "raster";
  s.gi.mode = gi::RadianceMode::RadianceCache;
  s.gi.parameters = nlohmann::json::object();
  s.lights.clear();
  s.environment.reset();
  for (auto& o : s.octrees) {
    o.colour = layer;
    if (scale) o.colourScale = *scale;
  }
  return renderOnce(s);
}

double sq(double v) {
  return v * v;
}

// sqrt(sum (t - r)^2 / sum r^2) over the pixels `use` picks (non-finite differences skipped).
template <class Pick>
double maskedRelativeL2(const HdrImage& t, const HdrImage& r, Pick use, size_t* count) {
  double num = 0, den = 0;
  size_t n = 0;
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      if (!use(x, y)) continue;
      ++n;
      const gi::Rgb a = t.get(x, y), b = r.get(x, y);
      for (int k = 0; k < 3; ++k) {
        const double d = double(a[k]) - double(b[k]);
        if (!std::isfinite(d)) continue;
        num += d * d, den += sq(b[k]);
      }
    }
  if (count) *count = n;
  return den > 0 ? std::sqrt(num / den) : (num > 0 ? INFINITY : 0.0);
}

HdrImage difference(const HdrImage& a, const HdrImage& b) {
  HdrImage d(a.width, a.height);
  for (size_t i = 0; i < d.rgb.size(); ++i) d.rgb[i] = a.rgb[i] - b.rgb[i];
  return d;
}

// Low-resolution blocks whose every pixel is a scan pixel (mask 1): dL there is the scan's alone,
// no edge of an inserted mesh or of the background inside.
std::vector<bool> wholeScanBlocks(const Truth& t) {
  const int s = t.scale, w = (t.mask.width + s - 1) / s, h = (t.mask.height + s - 1) / s;
  std::vector<bool> whole(size_t(w) * size_t(h), true);
  for (int y = 0; y < t.mask.height; ++y)
    for (int x = 0; x < t.mask.width; ++x)
      if (t.mask.get(x, y)[0] != 1.0f) whole[size_t(y / s) * size_t(w) + size_t(x / s)] = false;
  return whole;
}

}  // namespace

bool applies(const gi::Scene& scene) {
  const auto& p = scene.gi.parameters;
  if (!p.is_object() || !p.contains("capture") || !p["capture"].is_string() ||
      p["capture"].get<std::string>().empty())
    return false;
  return std::any_of(scene.meshes.begin(), scene.meshes.end(),
                     [](const gi::SceneMesh& m) { return m.inserted; });
}

gi::Scene withoutInserted(gi::Scene scene) {
  std::erase_if(scene.meshes, [](const gi::SceneMesh& m) { return m.inserted; });
  return scene;
}

void setGiParameter(gi::Scene& scene, const std::string& key, const nlohmann::json& value) {
  if (!scene.gi.parameters.is_object()) scene.gi.parameters = nlohmann::json::object();
  scene.gi.parameters[key] = value;
}

Truth makeTruth(const gi::Scene& scene, const HdrImage& r1, HdrImage r0, const fs::path& aovDir) {
  Truth t;
  // The mask and dL's resolution from diffrender itself, at its cheapest: the pixels it calls
  // scan and object are the ones its metrics are taken over.
  gi::Scene d = scene;
  d.gi.method = "diffrender";
  setGiParameter(d, "quality", "low");
  for (const char* key : {"samples", "cache", "object_samples"}) setGiParameter(d, key, 1);
  setGiParameter(d, "aovs", aovDir.string());
  renderOnce(d);
  t.mask = gi::readHdrImage((aovDir / "diffrender_mask.exr").string());
  const HdrImage delta = gi::readHdrImage((aovDir / "diffrender_delta.exr").string());
  if (t.mask.width != r1.width || t.mask.height != r1.height)
    throw Error("bench gi: diffrender's mask is " + std::to_string(t.mask.width) + "x" +
                std::to_string(t.mask.height) + ", the reference " + std::to_string(r1.width) +
                "x" + std::to_string(r1.height));
  for (t.scale = 1; t.scale <= 16; ++t.scale)
    if ((r1.width + t.scale - 1) / t.scale == delta.width &&
        (r1.height + t.scale - 1) / t.scale == delta.height)
      break;
  if (t.scale > 16) throw Error("bench gi: diffrender's dL image size gives no delta_scale");
  const std::string layer = scene.gi.parameters["capture"].get<std::string>();
  t.capture = scanColours(scene, layer, 1.0f);
  t.albedo = scanColours(scene, "rgb", std::nullopt);
  for (float& v : t.albedo.rgb) v = std::min(v, 1.0f);  // as the reference reads an albedo
  t.r1 = r1;
  t.change = difference(r1, r0);
  t.r0 = std::move(r0);
  t.r0Error = gi::relativeL2(t.r0, r1);
  size_t objectPixels = 0;
  t.r0ObjectError = maskedRelativeL2(
      t.r0, r1, [&](int x, int y) { return t.mask.get(x, y)[0] == 2.0f; }, &objectPixels);
  t.captureError = maskedRelativeL2(
      t.capture, t.r0, [&](int x, int y) { return t.mask.get(x, y)[0] == 1.0f; }, nullptr);
  const Metrics zero = measure(t.r0, HdrImage(delta.width, delta.height), nullptr, t);
  t.r0ChangeError = zero.deltaL2;
  t.info = {{"r0_relative_l2", t.r0Error},
            {"r0_object_l2", t.r0ObjectError},
            {"r0_delta_l2", t.r0ChangeError},
            {"capture_l2_scan", t.captureError},
            {"r0_relative_l2_box4", gi::relativeL2(gi::boxFilter(t.r0, 4), gi::boxFilter(r1, 4))},
            {"scan_blocks", zero.scanBlocks},
            {"object_pixels", objectPixels},
            {"delta_scale", t.scale},
            {"capture", layer},
            {"rule",
             "R1: the reference; R0: the reference without the inserted meshes. delta_l2: dL "
             "against R1 - R0, both as means of delta_scale x delta_scale blocks (diffrender "
             "computes dL at that resolution), over the blocks whose every pixel diffrender's "
             "mask calls scan; object_l2: the composite against R1 on the mask's inserted-mesh "
             "pixels; rho_l2: diffrender's material estimate against the scan's albedo (its "
             "colour capped at 1, drawn by the raster frame) on the same blocks; all relative "
             "L2"}};
  return t;
}

Metrics measure(const HdrImage& composite, const HdrImage& delta, const HdrImage* rho,
                const Truth& t) {
  Metrics m;
  const int s = t.scale;
  const std::vector<bool> whole = wholeScanBlocks(t);
  const HdrImage change = gi::boxFilter(t.change, s);
  auto low = [&](const HdrImage& img) {
    return img.width == change.width ? img : gi::boxFilter(img, s);
  };
  auto onScan = [&](int x, int y) { return bool(whole[size_t(y) * size_t(change.width) + x]); };
  m.deltaL2 = maskedRelativeL2(low(delta), change, onScan, &m.scanBlocks);
  m.objectL2 = maskedRelativeL2(
      composite, t.r1, [&](int x, int y) { return t.mask.get(x, y)[0] == 2.0f; }, &m.objectPixels);
  if (rho) m.rhoL2 = maskedRelativeL2(low(*rho), gi::boxFilter(t.albedo, s), onScan, nullptr);
  return m;
}

HdrImage twoSimulation(const HdrImage& with, const HdrImage& without, const Truth& t,
                       HdrImage& delta) {
  delta = difference(with, without);
  HdrImage out = with;
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      if (t.mask.get(x, y)[0] == 1.0f) out.set(x, y, t.capture.get(x, y) + delta.get(x, y));
  return out;
}

}  // namespace nestlight::bench::differential
