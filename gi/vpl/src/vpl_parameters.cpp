// `vpl`'s declaration: its parameters and its entry in the registry.
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/vpl/vpl_method.h"

namespace nestlight::gi {

const ParameterSpecs& vplParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::integer("vpls", 1, 65535, 1024,
                 "VPLs per generation, or auto: the count that fits target_ms per frame (a power "
                 "of two from 16 to the most the ISM atlas holds)")
          .orOneOf({"auto"}),
      P::number("target_ms", 0.1, 1e6, 33, "vpls auto: the frame time to fit"),
      P::integer("light_resolution", 16, 4096, 256, "light G-buffer texels per side and layer")
          .powersOfTwo(),
      P::integer("ism_size", 8, 512, 32, "texels per side of one ISM").powersOfTwo(),
      P::integer("ism_points", 16, 1 << 24, 2048, "points one ISM splats at most"),
      P::integer("pull_push", 0, 9, 3, "pull-push levels (0: none)"),
      P::integer("interleave", 1, 8, 4, "n: n x n VPL subsets"),
      P::number("clamp", 0, 1, 0.02,
                "clamp distance, as a fraction of the scene's bounding radius"),
      P::number("ism_bias", 0, 64, 1.5, "ISM depth bias, in texel footprints (slope-scaled)"),
      P::number("lod_scale", 0.125, 16, 1.0, "ISM points' spacing, in texel footprints"),
      P::number("energy_stop", 0, 1, 0.01,
                "stop bouncing when a generation re-emits less than this fraction"),
      P::choice("visibility", {"ism", "none", "exact"}, "ism",
                "ism (the method), none (every VPL sees everything) or exact (Embree rays on the "
                "CPU: separates the ISMs' error from the VPLs')"),
  };
  return specs;
}

VplParameters vplParameters(const Scene& scene) {
  const ResolvedParameters r = resolveParameterValues(scene, vplParameterSpecs());
  VplParameters p;
  if (r.value("vpls").is_string())
    p.autoCount = true;
  else
    p.count = int(r.integer("vpls"));
  p.targetMs = r.number("target_ms");
  p.lightResolution = int(r.integer("light_resolution"));
  p.ismSize = int(r.integer("ism_size"));
  p.ismPoints = int(r.integer("ism_points"));
  p.pullPushLevels = int(r.integer("pull_push"));
  p.interleave = int(r.integer("interleave"));
  p.clampFraction = float(r.number("clamp"));
  p.ismBias = float(r.number("ism_bias"));
  p.lodScale = float(r.number("lod_scale"));
  p.energyStop = r.number("energy_stop");
  const std::string v = r.string("visibility");
  p.visibility = v == "ism"    ? VplParameters::Visibility::Ism
                 : v == "none" ? VplParameters::Visibility::None
                               : VplParameters::Visibility::Exact;
  return p;
}

MethodInfo vplMethodInfo() {
  MethodInfo m;
  m.name = "vpl";
  m.summary =
      "real-time GI: importance-warped VPLs with imperfect shadow maps on the resident cut (GL)";
  m.gpu = true;
  m.qualityName = "VPLs";
  m.defaultQualities = {64, 256, 1024, 4096};
  m.applyQuality = [](GiSettings& g, int q) { setParameter(g, "vpls", q); };
  m.create = createVplMethod;
  m.variants = {{"1 bounce", [](GiSettings& g) { g.maxBounces = 1; }},
                {"2 bounces", [](GiSettings& g) { g.maxBounces = 2; }},
                {"3 bounces", [](GiSettings& g) { g.maxBounces = 3; }},
                {"exact visibility", [](GiSettings& g) { g.parameters["visibility"] = "exact"; }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), vplParameterSpecs().begin(), vplParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
