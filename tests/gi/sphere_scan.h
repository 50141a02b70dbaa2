// A closed sphere of scan points for GI tests (vpl, pbgi): furnaces and closed forms.
#pragma once

#include <cmath>
#include <fstream>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/gi/scene.h"
#include "test_support.h"

namespace nestlight::gi {

// A Fibonacci sphere of `n` scan points of radius R about the origin, normals inward, grey
// `grey` (8-bit sRGB), built into an octree at t/sphere.octree; only its points with z >= minZ
// (unit sphere) when minZ > -1; without normals when `normals` is false; nodes of at most
// maxNodePoints points (the converter's default when 0).
inline void buildSphereScan(const nestlight::test::TempDir& t, int n, float R, int grey,
                            float minZ = -1.0f, bool normals = true, uint32_t maxNodePoints = 0) {
  {
    std::ofstream ply(t.file("sphere.ply"));
    int kept = 0;
    for (int i = 0; i < n; ++i) kept += 1 - 2 * (i + 0.5) / n >= minZ;
    ply << "ply\nformat ascii 1.0\nelement vertex " << kept
        << "\nproperty float x\nproperty float y\nproperty float z\n"
        << (normals ? "property float nx\nproperty float ny\nproperty float nz\n" : "")
        << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    const double golden = kPi * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
      const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z), phi = golden * i;
      const double x = r * std::cos(phi), y = r * std::sin(phi);
      if (z < minZ) continue;
      ply << R * x << " " << R * y << " " << R * z << " ";
      if (normals) ply << -x << " " << -y << " " << -z << " ";
      ply << grey << " " << grey << " " << grey << "\n";
    }
  }
  nestlight::test::buildOctreeFrom(t.file("sphere.ply"), t.path() / "sphere.octree", maxNodePoints);
}

// A grey Lambert box of albedo rho (0.4 m, at the origin) inside the sphere scan (radiance-cache
// mode: the scan's colour is its light), seen from inside the sphere at 32 x 32, rendered by
// `method` with `parameters`.
inline Scene boxInSphereScene(const nestlight::test::TempDir& t, double rho,
                              const std::string& method, const nlohmann::json& parameters) {
  writeBoxObj(t.path() / "box.obj");
  nlohmann::json j = {
      {"version", 1},
      {"octrees", {{{"path", "sphere.octree"}}}},
      {"materials", {{"grey", {{"type", "lambert"}, {"base_color", rho}}}}},
      {"meshes", nlohmann::json::array({nlohmann::json{
                     {"path", "box.obj"},
                     {"transform", {{"translate", {-0.2, -0.2, -0.2}}, {"scale", {0.4, 0.4, 0.4}}}},
                     {"material", "grey"}}})},
      {"camera",
       {{"eye", {-0.55, 0.0, 0.0}},
        {"target", {0.0, 0.0, 0.0}},
        {"up", {0.0, 0.0, 1.0}},
        {"fov", 30.0},
        {"width", 32},
        {"height", 32}}},
      {"gi", {{"method", method}, {"mode", "radiance_cache"}, {"parameters", parameters}}}};
  std::ofstream(t.file("scene.json")) << j.dump(2);
  return loadScene(t.file("scene.json"));
}

}  // namespace nestlight::gi
