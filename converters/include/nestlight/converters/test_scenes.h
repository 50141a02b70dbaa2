// Scenes the project generates for the GI methods and their reference (issue 4): a seeded
// synthetic scan converted into an octree, inserted meshes written as OBJ, and a scene.json
// (docs/SCENE.md) that ties them together with a camera, lights and the GI settings.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace nestlight {

enum class TestSceneKind {
  Cornell,  // a closed room of coloured walls with a bright ceiling patch, two blocks and a
            // glossy sphere inserted on the floor; radiance-cache mode
  Nave,     // a nave with two colonnades, an inserted statue-like object; radiance-cache mode
  Object,   // the synthetic town scan with an inserted metal torus, under a sky and a sun;
            // albedo mode
  // The ground truth of differential rendering (Rohmer, Jendersie, Grosch 2017): the cornell
  // room's scan, lit by a captured emissive ceiling panel (a mesh with "inserted": false) or a
  // spot light, and one inserted object on the floor (the Stanford bunny where the shared data
  // have it, else a generated sphere); albedo mode, gi.method "diffrender"
  Diffrender,
};

// What lights the diffrender scene.
enum class DiffrenderLight { Panel, Spot };

struct TestSceneOptions {
  uint64_t points = 1'000'000;
  uint64_t seed = 1;
  int width = 320, height = 240;
  bool overwrite = false;
  bool quiet = false;
  // diffrender only. The spot by default: the reference finds it by next-event estimation, the
  // panel only when a path happens to hit it, so the panel's baked capture is far noisier.
  DiffrenderLight light = DiffrenderLight::Spot;
  // diffrender: the inserted object is sharedData/meshes/bunny.ply, copied into the folder, where
  // that file exists; otherwise (and with an empty path) a generated closed mesh, so the scene
  // never depends on data outside the project.
  std::filesystem::path sharedData;
};

// Writes dir/scan.octree, dir/*.obj and dir/scene.json; returns the scene file.
std::filesystem::path makeTestScene(TestSceneKind kind, const std::filesystem::path& dir,
                                    const TestSceneOptions& options);

std::optional<TestSceneKind> parseTestSceneKind(const std::string& name);
const char* testSceneKindName(TestSceneKind kind);

// Simple meshes written as OBJ (for inserted objects without shipping files).
void writeIcosphereObj(const std::filesystem::path& path, int subdivisions);
void writeTorusObj(const std::filesystem::path& path, double majorRadius, double minorRadius,
                   int segments, int sides);
void writeBoxObj(const std::filesystem::path& path);

}  // namespace nestlight
