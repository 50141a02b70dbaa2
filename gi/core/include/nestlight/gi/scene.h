// A scene: scans (octrees), inserted meshes with materials, lights, an environment map, cameras,
// the GI method and the outputs. Read from JSON (docs/SCENE.md); every value is checked and an
// error names the file and the field ("meshes[1].material.roughness: expected a number in
// [0, 1], got 1.5").
//
// Coordinates: the file is in world units (double). Everything that renders works in float
// relative to `origin` (the first scan's centre unless the file sets it), so a scan in
// national-grid coordinates keeps millimetre precision.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/camera_path.h"
#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/environment_sequence.h"
#include "nestlight/gi/material.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/octree/clip_volume.h"

namespace nestlight::gi {

struct SceneOctree {
  std::filesystem::path path;
  std::optional<int> maxLevel;         // deepest level loaded (none: all, within the budget)
  uint64_t memoryBudget = 2ull << 30;  // bytes of points the reference may hold
  float radiusScale = 1.0f;            // disc radius = radiusScale * local spacing
  float colourScale = 1.0f;            // radiance (or albedo) per unit of recorded colour
  // Where its colour comes from: "rgb" (recorded, sRGB decoded) or a colour layer ("hdr": the
  // HDR colour nestlight expand-hdr writes; nestlight/gi/scan_colour.h).
  std::string colour = "rgb";
  // Clipping volumes in the scan's own world coordinates (the array `export --clip` and view
  // states hold): what they remove is not part of the scene, for every method (the GL methods'
  // frame clips on the GPU and never loads nodes removed whole; the path tracer skips the points).
  ClipSet clipping;
};

struct SceneMesh {
  std::filesystem::path path;
  glm::dmat4 worldFromObject{1.0};
  uint32_t material = 0;  // index into Scene::materials
  SurfelSampling surfelMethod = SurfelSampling::AreaUniform;
  size_t surfelCount = 20000;
  // False: the mesh was there when the scan was made (a lamp, a light panel), so differential
  // rendering counts it as part of the captured scene; only inserted meshes make the difference.
  bool inserted = true;
};

enum class LightType { Point, Spot, Directional };

struct Light {
  LightType type = LightType::Point;
  glm::dvec3 position{0.0};
  glm::vec3 direction{0, 0, -1};  // spot axis, or the direction light travels (directional)
  Rgb intensity{1.0f};            // point/spot: W/sr; directional: irradiance W/m^2 (normal)
  float innerAngleDegrees = 30;   // spot: full intensity inside
  float outerAngleDegrees = 45;   // spot: zero outside (smoothstep between)
};

struct SceneEnvironment {
  std::filesystem::path path;  // empty with `constant` or `sequence`
  std::optional<Rgb> constant;
  // A video light probe (nestlight/gi/environment_sequence.h): a frame pattern or a folder, its
  // frame rate, and whether a bad frame is an error or plays the previous one again.
  std::filesystem::path sequence;
  double fps = 24;
  bool keepPreviousOnBadFrame = false;
  float rotationDegrees = 0;
  float scale = 1;
};

struct SceneCamera {
  glm::dvec3 eye{0.0}, target{0, 0, -1}, up{0, 0, 1};
  double fovYDegrees = 45;
  int width = 640, height = 480;
  // Seconds into the shot: which frame of an environment sequence lights this view
  // (EnvironmentSource::at). A camera path's frame f is at f / fps.
  double time = 0;
};

enum class RadianceMode { RadianceCache, Albedo };

struct GiSettings {
  std::string method = "reference";  // a registered method (nestlight/gi/methods.h)
  RadianceMode mode = RadianceMode::RadianceCache;
  int maxBounces = 4;              // path length in bounces after the camera hit
  int samplesPerPixel = 256;       // upper bound on samples
  double targetRelativeError = 0;  // stop when the estimated relative error falls below (0: off)
  double timeLimitSeconds = 0;     // stop after this long (0: off)
  uint64_t seed = 1;
  nlohmann::json parameters;  // method-specific, validated by the method
};

struct SceneOutput {
  std::filesystem::path exr;  // linear HDR
  std::filesystem::path png;  // tone-mapped, optional
  double exposure = 0;        // stops, for the PNG, when exposureSet
  bool exposureSet = false;   // the file gives output.exposure; else the PNG's is automatic
                              // (gi/tone_map.h choosePngExposure; the viewer starts at 0)
};

// How `nestlight view scene.json` draws the scene's scans (the real-time point rendering; the
// GI methods read `gi`). Names as `nestlight render` takes them.
struct SceneDisplay {
  std::optional<std::string> rasteriser;  // points | compute (none: the viewer's default)
  std::optional<std::string>
      splatting;  // hqs | basic, points rasteriser (none: the viewer's default)
  std::optional<float>
      pointSize;  // splat diameter in measured spacings (none: the viewer's default)
  std::optional<float> edlStrength;  // eye-dome lighting (0: off; none: the viewer's default)
};

struct Scene {
  std::filesystem::path file;  // where it was read from (relative paths resolve here)
  glm::dvec3 origin{0.0};
  bool originSet = false;
  std::vector<SceneOctree> octrees;
  std::vector<Material> materials;
  std::vector<SceneMesh> meshes;
  std::vector<Light> lights;
  std::optional<SceneEnvironment> environment;
  SceneCamera camera;
  bool cameraSet = false;  // the file has "camera" (renders need it or a camera path)
  CameraPath cameraPath;   // optional (empty: none); replaces `camera`'s eye/target per frame
  GiSettings gi;
  SceneDisplay display;
  SceneOutput output;

  // Float offset of a world position from the origin.
  glm::vec3 local(const glm::dvec3& world) const { return glm::vec3(world - origin); }
  glm::mat4 localFromObject(const SceneMesh& m) const;
};

// The cameras a render of `scene` draws: one per frame of its camera path (CameraPath::at, at
// time f / fps); without a path, one per frame of its environment sequence (the scene's camera at
// each frame's time), so every frame of a video light probe has its image; its camera alone when
// it has neither or `still` (time 0: a sequence's first frame). Throws nestlight::Error naming the
// scene file and field when there is no camera, the path asks for more than a million frames, or a
// frame's view is degenerate.
std::vector<SceneCamera> sceneCameras(const Scene& scene, bool still = false);

// What `e`'s sequence plays (its source, rate, rotation, scale, bad-frame rule).
EnvironmentSequenceSpec sequenceSpec(const SceneEnvironment& e);
// The environment map of `e` (path or sequence; not `constant`) at `seconds` into its sequence.
// Renders of a still take the sequence's first frame. Throws nestlight::Error naming the file.
EnvironmentMap loadEnvironmentAt(const SceneEnvironment& e, double seconds = 0);

// Throws nestlight::Error("scene.json", "scene.meshes[0].transform.scale", reason) on any
// fault. Relative paths resolve against the scene file's folder. Without "origin", the origin is
// the centre of the first octree's bounds (its metadata is read), else 0.
Scene loadScene(const std::filesystem::path& file);
// The same for a parsed document; `file` names it in messages and anchors relative paths. Reads
// no octree: the origin stays 0 unless the document sets it (see resolveOrigin()).
Scene parseScene(const nlohmann::json& j, const std::filesystem::path& file);
void resolveOrigin(Scene& scene);
// Whether anything emits light in `mode`: the scan itself (radiance-cache mode), a light, the
// environment, or an emissive material used by a mesh. In albedo mode a scene with none of these
// renders black.
bool sceneHasLight(const Scene& scene, RadianceMode mode);
// A camera can look from `eye` at `target`: they differ and the view is not parallel to `up`.
bool viewIsValid(const glm::dvec3& eye, const glm::dvec3& target, const glm::dvec3& up);

}  // namespace nestlight::gi
