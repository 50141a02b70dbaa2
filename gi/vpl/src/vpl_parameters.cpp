// `vpl`'s declaration: its parameters and its entry in the registry.
#include <map>
#include <tuple>

#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/vpl/vpl_method.h"
#include "nestlight/octree/error.h"

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

namespace {

// Whether the mesh is closed and every vertex lies on one side of each triangle's plane (either
// side: OBJ windings need not agree), within 1e-5 of its size: a convex surface, which cannot light
// itself. Unreadable, or too large to check here (more than 1e8 vertex-plane tests): no.
bool looksConvex(const std::filesystem::path& path) {
  TriangleMesh mesh;
  try {
    mesh = readMesh(path.string());
  } catch (const Error&) {
    return false;
  }
  const auto& v = mesh.positions;
  if (v.empty() || double(mesh.indices.size() / 3) * double(v.size()) > 1e8) return false;
  glm::vec3 lo = v[0], hi = v[0];
  for (const glm::vec3& p : v) lo = glm::min(lo, p), hi = glm::max(hi, p);
  // Closed: every edge, between vertices welded by position (seams repeat them), joins two
  // triangles. An open sheet may face itself (a fold) whatever its planes say.
  std::map<std::tuple<float, float, float>, uint32_t> weld;
  std::vector<uint32_t> id(v.size());
  for (size_t i = 0; i < v.size(); ++i)
    id[i] =
        weld.emplace(std::make_tuple(v[i].x, v[i].y, v[i].z), uint32_t(weld.size())).first->second;
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = id[mesh.indices[t + e]], b = id[mesh.indices[t + (e + 1) % 3]];
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [edge, n] : edges)
    if (n != 2) return false;
  const double tol = 1e-5 * double(glm::length(hi - lo));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const glm::dvec3 a = v[mesh.indices[t]], b = v[mesh.indices[t + 1]], c = v[mesh.indices[t + 2]];
    glm::dvec3 n = glm::cross(b - a, c - a);
    const double len = glm::length(n);
    if (!(len > 0)) continue;
    n /= len;
    bool above = false, below = false;
    for (const glm::vec3& p : v) {
      const double d = glm::dot(n, glm::dvec3(p) - a);
      above = above || d > tol, below = below || d < -tol;
      if (above && below) return false;
    }
  }
  return true;
}

// Why `bench gi`'s bounce variants would all render the scene's own image. In the radiance-cache
// mode a scan point's colour is the light leaving it, so light that reaches a scan point ends
// there (vpl_bounce.comp drops a bounce that hits one, as the reference ends its path), and scan
// pixels show their recorded colour: a generation after the first can only change the image by
// light that goes scan -> mesh -> mesh. With no inserted mesh, or a single convex one (a convex
// surface does not see itself), no mesh lights a mesh, and every bounce count (>= 1) renders the
// first generation's image: the generated cornell room (one sphere) is such a scene.
std::string bouncesMatter(const Scene& s) {
  if (s.gi.mode != RadianceMode::RadianceCache || s.meshes.size() > 1) return "";
  if (s.meshes.size() == 1 && !looksConvex(s.meshes[0].path)) return "";
  return "same image at any bounce count: in the radiance-cache mode light that reaches a scan "
         "point ends there, and the scene has " +
         std::string(s.meshes.empty() ? "no inserted mesh" : "one inserted mesh, convex,") +
         " so no mesh lights a mesh";
}

}  // namespace

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
  m.variants = {{"1 bounce", [](GiSettings& g) { g.maxBounces = 1; }, bouncesMatter},
                {"2 bounces", [](GiSettings& g) { g.maxBounces = 2; }, bouncesMatter},
                {"3 bounces", [](GiSettings& g) { g.maxBounces = 3; }, bouncesMatter},
                {"exact visibility", [](GiSettings& g) { g.parameters["visibility"] = "exact"; }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), vplParameterSpecs().begin(), vplParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
