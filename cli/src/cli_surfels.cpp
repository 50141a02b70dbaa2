// `nestlight surfels scene.json -o objects.ply`: the inserted meshes of a scene sampled into
// points (paper 004 section 6), so that they can be inspected, converted into an octree and lit
// by point-based GI beside the scan.
#include <cmath>
#include <cstdio>
#include <cstring>

#include "cli.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

void addSurfels(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("surfels",
                                 "Sample the inserted meshes of a scene into points (surfels) and "
                                 "write them as PLY or LAS: position,\n"
                                 "normal, colour (albedo, sRGB), `area` (m^2 of surface each point "
                                 "stands for; they sum to the\n"
                                 "mesh's area) and `material` (index into the scene's materials). "
                                 "Method and count per mesh come\n"
                                 "from the scene's \"surfels\" field unless given here.\n"
                                 "Example: nestlight surfels scene.json -o objects.ply && "
                                 "nestlight convert objects.ply -o objects.octree");
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto count = std::make_shared<std::string>();
  auto method = std::make_shared<std::string>();
  auto seed = std::make_shared<uint64_t>(1);
  cmd->add_option("scene", *scene, "Scene file (.json)")->required();
  cmd->add_option("-o,--output", *out, "Point file (.ply or .las)")->required();
  cmd->add_option("-n,--count", *count, "Points per mesh (e.g. 50k), instead of the scene's");
  cmd->add_option("--method", *method,
                  "area (uniform by area) or poisson (Poisson-disk, Yuksel 2015)")
      ->check(CLI::IsMember({"area", "poisson"}));
  cmd->add_option("--seed", *seed, "Random seed")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    gi::Scene s = gi::loadScene(*scene);
    gi::checkSceneMethod(s);  // the registry names the methods, not the scene parser
    if (s.meshes.empty()) throw Error(*scene, "scene.meshes", "the scene inserts no meshes");
    SourceHeader h;
    h.path = *out;
    h.format = "surfels";
    const size_t rgbOff = h.layout.stride();
    h.layout.add({std::string(attr::kRgb), ScalarType::U16, 3, "albedo, sRGB-encoded"});
    const size_t nOff = h.layout.stride();
    h.layout.add({std::string(attr::kNormal), ScalarType::F32, 3, "surface normal"});
    const size_t areaOff = h.layout.stride();
    h.layout.add({"area", ScalarType::F32, 1, "surface area the point stands for (world units^2)"});
    const size_t matOff = h.layout.stride();
    h.layout.add({"material", ScalarType::U32, 1, "index into the scene's materials"});
    h.rgbBits = 16;
    h.scale = Vec3d{1e-4, 1e-4, 1e-4};
    h.offset = Vec3d{s.origin.x, s.origin.y, s.origin.z};
    auto writer = createWriter(*out, h);
    const size_t stride = h.layout.stride();
    uint64_t total = 0;
    double totalArea = 0;
    for (size_t mi = 0; mi < s.meshes.size(); ++mi) {
      const gi::SceneMesh& m = s.meshes[mi];
      gi::TriangleMesh mesh = gi::readMesh(m.path.string());
      gi::SurfelOptions so;
      so.method = method->empty() ? m.surfelMethod
                                  : (*method == "poisson" ? gi::SurfelSampling::PoissonDisk
                                                          : gi::SurfelSampling::AreaUniform);
      so.count = count->empty() ? m.surfelCount : size_t(parseCount(*count, "--count"));
      so.seed = *seed + mi;
      so.material = m.material;
      so.baseColor = s.materials[m.material].baseColor;
      // Sampled in the local frame, written back in world coordinates through double.
      gi::Surfels sf = gi::sampleSurfels(mesh, s.localFromObject(m), so);
      PointBatch b;
      const size_t n = sf.positions.size();
      b.xyz.resize(3 * n);
      b.attrs.assign(n * stride, 0);
      for (size_t i = 0; i < n; ++i) {
        for (int a = 0; a < 3; ++a) b.xyz[3 * i + a] = s.origin[a] + double(sf.positions[i][a]);
        uint8_t* p = &b.attrs[i * stride];
        uint16_t c[3];
        for (int a = 0; a < 3; ++a)
          c[a] = uint16_t(std::lround(gi::srgbEncode(sf.albedo[i][a]) * 65535.0f));
        std::memcpy(p + rgbOff, c, 6);
        std::memcpy(p + nOff, &sf.normals[i], 12);
        std::memcpy(p + areaOff, &sf.area[i], 4);
        std::memcpy(p + matOff, &sf.material[i], 4);
        totalArea += sf.area[i];
      }
      writer->write(b);
      total += n;
      std::printf("surfels: %s: %zu points (%s), %.6g m^2\n", m.path.c_str(), n,
                  so.method == gi::SurfelSampling::PoissonDisk ? "Poisson-disk" : "uniform by area",
                  gi::meshArea(mesh, s.localFromObject(m)));
    }
    writer->close();
    std::printf("surfels: wrote %s: %llu points standing for %.6g m^2\n", out->c_str(),
                (unsigned long long)total, totalArea);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
