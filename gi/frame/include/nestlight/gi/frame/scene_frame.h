// The raster frame as a base for other real-time GI methods: `raster` loads the scene (scans
// streamed under budgets, meshes, lights with their shadow maps, materials) and builds the GI
// frame's passes for the camera's G-buffer and direct light; a method that adds indirect light
// (VPLs, hierarchies) is a FrameExtension that adds its own passes to the same frame graph and
// reads what the frame offers through SceneFrame. The method is made by
// createRasterMethod(scene, ctx, extension).
#pragma once

#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/interface.h"
#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/scan_colour.h"
#include "nestlight/gl/program.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/metadata.h"

namespace nestlight::gi {

// One drawn node of the lights' cut (the whole scan at about a shadow map's resolution, the
// same for every camera): its points buffer in the GPU point layout (NL_POINT_WORDS words).
struct CutNode {
  unsigned buffer = 0;  // GL buffer name of its points
  uint32_t numPoints = 0;
  glm::vec3 origin{0.0f};  // the node's cube origin, scene-local
  float size = 0;          // the cube's edge
  float spacing = 0;       // nominal spacing of its level
  int parent = -1;         // index of its parent in the same list (-1: a root)
  float colourScale = 1;   // its scan's colour_scale
  bool hdrColour = false;  // its colour words are RGB9E5 (shaders/common/colour_word.glsl)
  int scan = 0;            // which scan (bindLightsCutTree)
  int indexInScan = 0;     // its entry in that scan's lights'-cut draw tree
  uint64_t handle = 0;     // its store handle (layerBuffer)
  // Its scan's clipping volumes cut through its cube: a shader reading its points tests each
  // (shaders/common/clip_volumes.glsl, uClipTest 1, after bindScanClip). Nodes they remove whole
  // are not in the cut.
  bool clipTest = false;
};

class SceneFrame {
 public:
  virtual ~SceneFrame() = default;
  virtual const Scene& scene() const = 0;
  virtual const FrameParameters& frameParameters() const = 0;
  virtual frame::FrameGraph& graph() = 0;
  // The scene's bounds in its local frame (scans and meshes).
  virtual glm::vec3 boundsLo() const = 0;
  virtual glm::vec3 boundsHi() const = 0;
  // The lights, and per shadow-map layer its clip-from-world and view-from-world (spot: one
  // perspective layer, point: six cube faces, directional: one orthographic layer over the
  // clusters of objects the camera sees, shadow_fit.h's clusterObjects, refitted when that set
  // changes; unless FrameExtension::shadowsForTheCameraOnly: then over what the camera sees,
  // refitted every frame).
  virtual const std::vector<frame::LightRecord>& lights() const = 0;
  virtual const std::vector<glm::mat4>& lightClipFromWorld() const = 0;
  virtual const std::vector<glm::mat4>& lightViewFromWorld() const = 0;
  // The bounds of the clusters the directional views span now (the scene's bounds while it is
  // one cluster), and a count that changes whenever any light view or record does: what an
  // extension derives from them (inverses, distances relative to the scene's size) is stale then.
  virtual glm::vec3 lightViewBoundsLo() const = 0;
  virtual glm::vec3 lightViewBoundsHi() const = 0;
  virtual uint64_t lightViewsGeneration() const = 0;
  // Binds the lights (NL_SSBO_LIGHTS), light views (NL_SSBO_SHADOW_VIEWS) and materials
  // (NL_SSBO_MATERIALS).
  virtual void bindSceneBuffers() const = 0;
  // Sets shaders/gi/common/environment.glsl's uniforms of the bound `program` and binds the map
  // to texture unit 5. Direct light already holds the environment's unshadowed light on every
  // lobe (irradiance on diffuse lobes, the prefiltered sky on glossy ones) and what the camera
  // sees of it behind the scene.
  virtual void bindEnvironment(const gl::ShaderProgram& program) const = 0;
  virtual bool hasEnvironment() const = 0;
  // The environment map the frame lights with now (a video light probe's current frame; a black
  // map without an environment), and a count that changes whenever it does.
  virtual std::shared_ptr<const EnvironmentMap> environmentMap() const = 0;
  virtual uint64_t environmentGeneration() const = 0;
  // Whether direct light adds the sky's unshadowed light to every lobe (the default); an
  // extension that gathers the sky itself, occluded by the scene, turns it off in setUp.
  virtual void setSkyInDirectLight(bool on) = 0;
  // Draws the scans' splats (shaders/points/points.vert, compiled with NL_SCENE_FRAME 1, with
  // `program`'s fragment stage): the camera's cut or the lights' cut.
  virtual void drawScans(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                         const glm::mat4& viewFromWorld, float pixelsPerUnit, bool orthographic,
                         bool lightsCut) = 0;
  // Draws the meshes (shaders/gi/raster/mesh.vert), with their materials' uniforms or without.
  virtual void drawMeshes(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                          bool materials) = 0;
  // The same for the scene's meshes `include` accepts (by index in Scene::meshes): differential
  // rendering draws the captured scene's meshes apart from the inserted ones.
  virtual void drawMeshesWhere(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                               bool materials, const std::function<bool(size_t)>& include) = 0;
  // The lights' cut of every scan, parents before children; changes only when the cut does
  // (cutGeneration() counts the changes).
  virtual const std::vector<CutNode>& lightsCut() const = 0;
  virtual uint64_t cutGeneration() const = 0;
  // A new generation whenever the camera's cut (the nodes the G-buffer draws) changes: with the
  // camera, the lights' cut and the environment, what an extension refining one view over
  // several frames (projection's progressive frames) must start again on.
  virtual uint64_t viewGeneration() const = 0;
  // Whether the frame being rendered is a still (render) or an interactive frame.
  virtual bool still() const = 0;
  // Binds scan `scan`'s lights'-cut draw tree (NL_SSBO_DRAW_TREE: points/splat_size.glsl's
  // finestSpacing() then works for that scan's CutNodes).
  virtual void bindLightsCutTree(int scan) const = 0;
  // Binds scan `scan`'s clipping volumes (the scene's octrees[].clipping) at NL_UBO_CLIP in the
  // scene's local frame, for shaders/common/clip_volumes.glsl; nothing when it has none (its
  // CutNodes' clipTest is false then).
  virtual void bindScanClip(int scan) const = 0;
  // Adds a per-node layer (a hierarchy over the node's points) to every scan's store, made for
  // that scan's metadata, colour source (the scene's octrees[].colour) and clipping volumes (none:
  // null; a layer leaves out the points they remove, ClipSet::keeps): from then on loader
  // threads build it with each node, it is uploaded and freed with the node and counted in the
  // budgets. Call in setUp, before the first frame streams anything. Returns the layer's index (the
  // same for every scan).
  using NodeLayerFactory = std::function<std::shared_ptr<const frame::NodeLayer>(
      const Metadata&, std::shared_ptr<const ScanColours>, std::shared_ptr<const ClipSet>)>;
  virtual size_t addNodeLayer(const NodeLayerFactory& make) = 0;
  // A cut node's layer buffer (GL name; 0 when it has none) and its bytes.
  virtual unsigned layerBuffer(const CutNode& node, size_t layer) const = 0;
  virtual size_t layerBytes(const CutNode& node, size_t layer) const = 0;
  virtual bool quiet() const = 0;
  // The scene's meshes as read from their files, one per scene mesh in scene order (surfel
  // samplers start from them instead of reading the files again). Only during setUp: the frame
  // drops them afterwards.
  virtual const std::vector<TriangleMesh>& meshes() const = 0;
};

class FrameExtension {
 public:
  virtual ~FrameExtension() = default;
  virtual std::string name() const = 0;
  // gi.parameters keys the extension reads (beside raster's); parse them in setUp.
  virtual std::vector<std::string> parameterKeys() const = 0;
  // Called once the scene is loaded: validates the extension's parameters, adds its passes after
  // direct light (the "radiance" target holds direct light and what the camera sees of the
  // environment) and returns the target to tone map and read back.
  virtual std::string setUp(SceneFrame& frame) = 0;
  // Before each frame executes, after the cuts are streamed.
  virtual void beforeFrame(SceneFrame& frame) { (void)frame; }
  // After each frame: attributes and a summary of the extension's own (appended to raster's).
  virtual void describe(const SceneFrame& frame, MethodFrame& f) const { (void)frame, (void)f; }
  // After a still's read-back (`rgba`: the output target's pixels, alpha included).
  virtual void afterReadBack(const std::vector<float>& rgba, MethodFrame& f) {
    (void)rgba, (void)f;
  }
  // After every frame, still or interactive, with its wall time (GPU work finished for stills).
  // A still is rendered again while this returns true (an extension tuning itself, at most 4
  // times).
  virtual bool afterFrame(double seconds, bool still) {
    (void)seconds, (void)still;
    return false;
  }
  virtual std::vector<std::pair<std::string, std::string>> parameters() const { return {}; }
  // Stills render at this many times the camera's width and height (its cut chosen for that
  // size too) and are box-filtered back: supersampling for extensions whose paper asks for it.
  virtual int supersample() const { return 1; }
  // True when the extension reads the shadow maps only at the camera's pixels (as raster's direct
  // light does): directional lights' maps are then fitted to the camera's view each frame
  // (shadow_fit.h), sharp however far the scene's objects lie apart. False keeps each over the
  // whole clusters of objects the camera sees, fixed while that set does not change, for
  // extensions that light what the camera does not see (VPLs' light views, PBGI's lit
  // hierarchies): points outside a map (other clusters) are lit, unshadowed.
  virtual bool shadowsForTheCameraOnly() const { return false; }
};

// `raster` with `extension`'s passes (nullptr: raster alone); the method takes its name.
std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx,
                                           std::unique_ptr<FrameExtension> extension);

}  // namespace nestlight::gi
