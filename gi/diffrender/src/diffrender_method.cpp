// The `diffrender` method (nestlight/gi/diffrender/diffrender_method.h): Rohmer, Jendersie and
// Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality for Mobile and
// non-Mobile Devices" (IEEE TVCG 2017), sections 5 to 7, as passes of the raster frame: a
// distance impostor of the captured scene at the inserted meshes' centre (rebuilt when the
// lights' cut or the environment changes), the meshes' solid voxel volume (built once), dL on the
// scan at 1 / delta_scale, and the composite with the inserted meshes' own light
// (shaders/gi/diffrender/).
#include "nestlight/gi/diffrender/diffrender_method.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <utility>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/gi/diffrender/object_volume.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/shared/bsh_layer.h"
#include "nestlight/gi/shared/cut_hierarchies.h"
#include "nestlight/gi/shared/reference_scene.h"
#include "nestlight/gi/shared/triangle_bvh.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"

// The passes' counters and slots (shaders/gi/diffrender/diffrender_interface.glsl).
#include "gi/diffrender/diffrender_interface.glsl"

namespace nestlight::gi {

namespace {

// Holes up to 2^5 = 32 texels wide are filled from their surroundings; wider empty regions are
// the environment (impostor_fill.comp).
constexpr int kFillLevels = 5;

// Depth-tested splats and triangles into a size x size target, as the frame's shadow maps draw.
void beginDepthDraw(int size) {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glViewport(0, 0, size, size);
}

int levelsFor(int size) {
  int levels = 1;
  while ((size >> levels) > 0) ++levels;
  return levels;
}

// The exact query's discs are the reference's (assignDiscRadii: each covers its Voronoi cell on
// its surface), so that its rays meet the surfaces the reference's do: with the octree level's
// spacing as radius, which is the least distance between a level's points and not the farthest a
// surface lies from them, 28% of its rays in a closed room of points 4 cm apart at random passed
// between discs. Here per node, from the node's own points (a coarser set than the reference's
// whole levels, so its cells are wider): a point alone in its node, or among copies, keeps the
// level's spacing.
std::vector<float> exactDiscRadii(const BshPoints& in, float leafRadius) {
  std::vector<float> radius(in.position.size(), leafRadius);
  std::vector<glm::vec4> discs;
  std::vector<glm::vec3> normals;
  std::vector<uint32_t> of;
  discs.reserve(in.position.size());
  for (uint32_t i = 0; i < in.position.size(); ++i) {
    const glm::vec3& p = in.position[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) continue;
    discs.emplace_back(p, 0.0f);
    if (!in.normal.empty()) normals.push_back(in.normal[i]);
    of.push_back(i);
  }
  assignDiscRadii(discs, normals, 1.0f);
  for (size_t k = 0; k < discs.size(); ++k)
    if (discs[k].w > 0 && std::isfinite(discs[k].w)) radius[of[k]] = discs[k].w;
  return radius;
}

class DiffrenderExtension : public FrameExtension {
 public:
  DiffrenderExtension(const Scene& scene, DiffrenderParameters params)
      : params_(std::move(params)), seed_(uint32_t(scene.gi.seed)) {}

  std::string name() const override { return "diffrender"; }
  // The scene's lights are raster's direct light, read at the camera's pixels only.
  bool shadowsForTheCameraOnly() const override { return true; }
  std::vector<std::string> parameterKeys() const override {
    return parameterNames(diffrenderParameterSpecs());
  }

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    const glm::ivec3 v = params_.objectVoxels;
    return {{"query", queryName(params_.query)},
            {"quality", qualityName(params_.quality)},
            {"samples", std::to_string(params_.samples)},
            {"object_samples", std::to_string(params_.objectSamples)},
            {"cache", std::to_string(params_.cache)},
            {"object_voxels",
             std::to_string(v.x) + "x" + std::to_string(v.y) + "x" + std::to_string(v.z)},
            {"self_shadow", params_.selfShadow ? "true" : "false"},
            {"secondary_bounce", params_.secondaryBounce ? "true" : "false"},
            {"impostor_size", std::to_string(params_.impostorSize)},
            {"delta_scale", std::to_string(params_.deltaScale)},
            {"ambient", std::to_string(params_.ambient)},
            {"rho_max", std::to_string(params_.rhoMax)},
            {"material", params_.materialEstimate ? "estimate" : "colour"},
            {"dit_iterations", std::to_string(params_.ditIterations)},
            {"aovs", params_.aovs}};
  }

  std::string setUp(SceneFrame& f) override {
    // The objects gather the sky through the impostor, whose empty texels show it: direct light
    // must not add its unshadowed light too.
    f.setSkyInDirectLight(false);
    buildVolume(f);
    sceneLo_ = f.boundsLo(), sceneHi_ = f.boundsHi(), sceneFile_ = f.scene().file.string();
    const int S = params_.impostorSize;
    raw_ = gl::Texture::array2d(GL_RGBA32F, S, S, 6);
    colourSum_ = gl::Texture::array2d(GL_RGBA32F, S, S, 6, levelsFor(S));
    distanceSum_ = gl::Texture::array2d(GL_R32F, S, S, 6, levelsFor(S));
    // Mipmapped filters: texelFetch of a level beyond the base is undefined without them.
    colourSum_.setFilter(GL_NEAREST_MIPMAP_NEAREST, GL_NEAREST);
    distanceSum_.setFilter(GL_NEAREST_MIPMAP_NEAREST, GL_NEAREST);
    rawDepth_ = gl::Texture(GL_DEPTH_COMPONENT32F, S, S);
    impostorLevels_ = levelsFor(S);
    impostor_ = gl::Texture::cubeMap(GL_RGBA32F, S, impostorLevels_);
    impostor_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
    glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
    impostorFbo_ = gl::Framebuffer::create();
    impostorScan_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "points/points.vert"},
                                       {GL_FRAGMENT_SHADER, "gi/diffrender/impostor_scan.frag"}},
                                      {{"NL_SCENE_FRAME", "1"}});
    impostorMesh_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "gi/raster/mesh.vert"},
                                       {GL_FRAGMENT_SHADER, "gi/diffrender/impostor_mesh.frag"}});
    pull_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/impostor_pull.comp"}});
    fill_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/impostor_fill.comp"}});
    delta_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/diffrender_delta.comp"}});
    compose_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/diffrender_compose.comp"}});
    stats_ = gl::Buffer(DR_STAT_COUNT * 4);
    if (!params_.background.empty()) loadBackground(f);
    meshShadow_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "gi/raster/mesh.vert"},
                                     {GL_FRAGMENT_SHADER, "gi/raster/depth_only.frag"}});
    scanShadow_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "points/points.vert"},
                                     {GL_FRAGMENT_SHADER, "gi/raster/shadow_scan.frag"}},
                                    {{"NL_SCENE_FRAME", "1"}});
    shadowFbo_ = gl::Framebuffer::create();
    frame::FrameGraph& g = f.graph();
    g.addBuffer("diffrender_shadows");
    g.addPass(
        "diffrender_shadows", frame::Scope::Frame,
        [](frame::PassBuilder& b) {
          b.read("shadow_maps");
          b.write("diffrender_shadows");
        },
        [this, &f](const frame::PassContext&) { renderShadowsWithout(f); });
    g.addBuffer("diffrender_impostor");
    g.addPass(
        "diffrender_impostor", frame::Scope::Frame,
        [](frame::PassBuilder& b) { b.write("diffrender_impostor"); },
        [this, &f](const frame::PassContext&) { renderImpostor(f); });
    if (tracesExactly()) {
      // The scan's hierarchies, unpruned (every leaf a point's disc, as wide as the reference's:
      // exactDiscRadii), built per node by the loader threads and joined under a top tree when
      // the cut changes (beforeFrame).
      layer_ = f.addNodeLayer([](const Metadata& meta, std::shared_ptr<const ScanColours> c,
                                 std::shared_ptr<const ClipSet> clip) {
        BshOptions o;
        o.prune = false;
        o.discRadii = exactDiscRadii;
        return std::make_shared<BshLayer>(meta, o, std::move(c), std::move(clip));
      });
      buildCapturedMeshBvh(f);
    }
    if (params_.query == DiffrenderParameters::Query::Vct) {
      setUpSceneVolume();
      g.addBuffer("diffrender_scene_volume");
      g.addPass(
          "diffrender_scene_volume", frame::Scope::Frame,
          [](frame::PassBuilder& b) { b.write("diffrender_scene_volume"); },
          [this, &f](const frame::PassContext&) { buildSceneVolume(f); });
    }
    g.addTarget("radiance_diffrender", {GL_RGBA32F});
    g.addPass(
        "diffrender_shade", frame::Scope::Tile,
        [this](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "radiance",
                                "shadow_maps", "diffrender_shadows", "diffrender_impostor"})
            b.read(t);
          if (params_.query == DiffrenderParameters::Query::Vct) b.read("diffrender_scene_volume");
          b.write("radiance_diffrender");
        },
        [this, &f](const frame::PassContext& ctx) { shade(f, ctx); });
    return "radiance_diffrender";
  }

  void afterReadBack(const std::vector<float>&, MethodFrame& f) override {
    if (params_.aovs.empty() || aovMask_.width == 0) return;
    std::error_code ec;
    std::filesystem::create_directories(params_.aovs, ec);
    const std::filesystem::path dir(params_.aovs);
    writeExr((dir / "diffrender_delta.exr").string(), aovDelta_);
    writeExr((dir / "diffrender_rho.exr").string(), aovRho_);
    writeExr((dir / "diffrender_mask.exr").string(), aovMask_);
    f.attributes["nestlight:diffrender_aovs"] = params_.aovs;
  }

  void beforeFrame(SceneFrame& f) override {
    if (tracesExactly() && f.cutGeneration() != hierCut_) {
      hierCut_ = f.cutGeneration();
      hier_.assemble(f, layer_);
    }
    objectLightStale_ = true;
    std::array<uint32_t, DR_STAT_COUNT> zeros{};
    stats_.upload(zeros.data(), sizeof zeros);
  }

  void describe(const SceneFrame&, MethodFrame& mf) const override {
    std::array<uint32_t, DR_STAT_COUNT> s{};
    glGetNamedBufferSubData(stats_.id(), 0, sizeof s, s.data());
    auto& a = mf.attributes;
    a["nestlight:diffrender_query"] = queryName(params_.query);
    a["nestlight:diffrender_scan_pixels"] = std::to_string(s[DR_STAT_SCAN_PIXELS]);
    a["nestlight:diffrender_object_pixels"] = std::to_string(s[DR_STAT_OBJECT_PIXELS]);
    a["nestlight:diffrender_rho_clamped"] = std::to_string(s[DR_STAT_RHO_CLAMPED]);
    a["nestlight:diffrender_dit_unconverged"] = std::to_string(s[DR_STAT_UNCONVERGED]);
    a["nestlight:diffrender_dit_hidden"] = std::to_string(s[DR_STAT_HIDDEN]);
    a["nestlight:diffrender_box_hits"] = std::to_string(s[DR_STAT_BOX_HITS]);
    a["nestlight:diffrender_traced"] = std::to_string(s[DR_STAT_TRACED]);
    a["nestlight:diffrender_object_first"] = std::to_string(s[DR_STAT_OBJECT_FIRST]);
    a["nestlight:diffrender_self_shadowed"] = std::to_string(s[DR_STAT_SELF_SHADOWED]);
    if (params_.compareExact) {
      a["nestlight:diffrender_compared"] = std::to_string(s[DR_STAT_COMPARED]);
      a["nestlight:diffrender_within_footprint"] = std::to_string(s[DR_STAT_WITHIN_FOOTPRINT]);
      a["nestlight:diffrender_compared_seen"] = std::to_string(s[DR_STAT_COMPARED_SEEN]);
      a["nestlight:diffrender_within_footprint_seen"] = std::to_string(s[DR_STAT_WITHIN_SEEN]);
    }
    a["nestlight:diffrender_solid_voxels"] = std::to_string(solidVoxels_);
    a["nestlight:diffrender_impostor_builds"] = std::to_string(impostorBuilds_);
    char line[256];
    std::snprintf(line, sizeof line,
                  "; diffrender %s: %u scan samples (%u box hits, %u traced), %u object pixels, "
                  "%u rho clamped, DIT lookups: %u unconverged, %u from points the impostor hides",
                  queryName(params_.query), s[DR_STAT_SCAN_PIXELS], s[DR_STAT_BOX_HITS],
                  s[DR_STAT_TRACED], s[DR_STAT_OBJECT_PIXELS], s[DR_STAT_RHO_CLAMPED],
                  s[DR_STAT_UNCONVERGED], s[DR_STAT_HIDDEN]);
    mf.summary += line;
    if (params_.compareExact) {
      std::snprintf(
          line, sizeof line,
          "; compared with exact rays: %u of %u hits within an impostor texel's footprint (%u of "
          "the %u the impostor holds)",
          s[DR_STAT_WITHIN_FOOTPRINT], s[DR_STAT_COMPARED], s[DR_STAT_WITHIN_SEEN],
          s[DR_STAT_COMPARED_SEEN]);
      mf.summary += line;
    }
    for (const std::string& w : warnings_) mf.summary += "; warning: " + w;
  }

 private:
  // exact: the captured scene's meshes (inserted false) as a triangle BVH in the scene-local frame,
  // each triangle's material index in v0.w.
  void buildCapturedMeshBvh(SceneFrame& f) {
    const Scene& scene = f.scene();
    std::vector<glm::vec3> corners;
    std::vector<uint32_t> materials;  // per input triangle
    for (size_t i = 0; i < scene.meshes.size() && i < f.meshes().size(); ++i) {
      if (scene.meshes[i].inserted) continue;
      const glm::mat4 localFromObject = scene.localFromObject(scene.meshes[i]);
      const auto& m = f.meshes()[i];
      for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
        for (size_t c = 0; c < 3; ++c)
          corners.push_back(
              glm::vec3(localFromObject * glm::vec4(m.positions[m.indices[k + c]], 1.0f)));
        materials.push_back(uint32_t(scene.meshes[i].material));
      }
    }
    TriangleBvh bvh = buildTriangleBvh(corners);
    for (BvhTriangle& t : bvh.triangles)
      t.v0.w = std::bit_cast<float>(materials[std::bit_cast<uint32_t>(t.v0.w)]);
    NL_CHECK_MSG(bvh.nodes.size() * sizeof(BvhNode) <= gl::kMaxSsboRange &&
                     bvh.triangles.size() * sizeof(BvhTriangle) <= gl::kMaxSsboRange,
                 "diffrender: the captured meshes' BVH exceeds one 128 MiB buffer range");
    meshBvhNodes_ = GLint(bvh.nodes.size());
    meshBvh_ = gl::Buffer(std::max<size_t>(bvh.nodes.size(), 1) * sizeof(BvhNode),
                          bvh.nodes.empty() ? nullptr : bvh.nodes.data(), 0);
    meshTriangles_ = gl::Buffer(std::max<size_t>(bvh.triangles.size(), 1) * sizeof(BvhTriangle),
                                bvh.triangles.empty() ? nullptr : bvh.triangles.data(), 0);
  }

  // The exact query's hierarchies are built for it and for compare_exact's check of the others.
  bool tracesExactly() const {
    return params_.query == DiffrenderParameters::Query::Exact || params_.compareExact;
  }

  // The photograph, linear (a PNG's display values decoded with gamma 2.2, colour-match's
  // convention), rows bottom up as the frame's.
  void loadBackground(SceneFrame& f) {
    const std::filesystem::path file(params_.background);
    HdrImage photo =
        file.extension() == ".png" ? readPng(file.string()) : readHdrImage(file.string());
    if (file.extension() == ".png")
      for (float& v : photo.rgb) v = std::pow(std::max(v, 0.0f), 2.2f);
    std::vector<float> rgba(size_t(photo.width) * size_t(photo.height) * 4);
    for (int y = 0; y < photo.height; ++y)
      for (int x = 0; x < photo.width; ++x) {
        const Rgb c = photo.get(x, photo.height - 1 - y);
        float* o = &rgba[(size_t(y) * size_t(photo.width) + size_t(x)) * 4];
        o[0] = c.r, o[1] = c.g, o[2] = c.b, o[3] = 1;
      }
    background_ = gl::Texture(GL_RGBA32F, photo.width, photo.height);
    glTextureSubImage2D(background_.id(), 0, 0, 0, photo.width, photo.height, GL_RGBA, GL_FLOAT,
                        rgba.data());
    backgroundFile_ = f.scene().file.string();
  }

  // The inserted meshes' solid voxels (object_volume.h), one grid each.
  void buildVolume(SceneFrame& f) {
    const Scene& scene = f.scene();
    std::vector<VolumeMesh> inserted;
    for (size_t i = 0; i < scene.meshes.size() && i < f.meshes().size(); ++i) {
      if (!scene.meshes[i].inserted) continue;
      VolumeMesh v;
      v.mesh = &f.meshes()[i];
      v.localFromObject = scene.localFromObject(scene.meshes[i]);
      v.material = scene.meshes[i].material;
      v.name = "meshes[" + std::to_string(i) + "].path (" +
               scene.meshes[i].path.filename().string() + ")";
      inserted.push_back(v);
    }
    insertedMesh_.assign(scene.meshes.size(), false);
    for (size_t i = 0; i < scene.meshes.size(); ++i) insertedMesh_[i] = scene.meshes[i].inserted;
    if (inserted.empty())
      throw Error(scene.file.string(), "scene.meshes",
                  "diffrender renders the change inserted meshes make, and the scene has none "
                  "(every mesh has \"inserted\": false, or there are no meshes)");
    for (const VolumeMesh& v : inserted)
      if (v.material > 254)
        throw Error(scene.file.string(), "scene.materials",
                    "diffrender keeps at most 255 materials on inserted meshes");
    // One grid per mesh, each over its own box (one grid over distant meshes' joint box spends
    // its voxels on the air between them), stacked along z in one texture.
    if (inserted.size() > size_t(DR_VOLUMES_MAX))
      throw Error(scene.file.string(), "scene.meshes",
                  std::to_string(inserted.size()) +
                      " inserted meshes: diffrender voxelises at most " +
                      std::to_string(DR_VOLUMES_MAX));
    const glm::ivec3 n = params_.objectVoxels;
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &maxSize);
    const double bytes = double(n.x) * n.y * n.z * 5.0 * double(inserted.size());
    if (n.z * int(inserted.size()) > maxSize || bytes > double(128 << 20))
      throw Error(scene.file.string(), "scene.gi.parameters.object_voxels",
                  "the inserted meshes' grids (" + std::to_string(inserted.size()) + " of " +
                      std::to_string(n.x) + "x" + std::to_string(n.y) + "x" + std::to_string(n.z) +
                      ") exceed the 3D texture limit or 128 MiB: use fewer "
                      "voxels");
    const size_t per = size_t(n.x) * size_t(n.y) * size_t(n.z);
    std::vector<uint8_t> occupancy(per * inserted.size());
    std::vector<uint32_t> surface(per * inserted.size());
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    volumeLo_.clear(), volumeHi_.clear();
    solidVoxels_ = 0;
    warnings_.clear();
    for (size_t k = 0; k < inserted.size(); ++k) {
      const ObjectVolume vol = voxelizeSolid({inserted[k]}, n);
      std::copy(vol.occupancy.begin(), vol.occupancy.end(),
                occupancy.begin() + std::ptrdiff_t(k * per));
      std::copy(vol.surface.begin(), vol.surface.end(), surface.begin() + std::ptrdiff_t(k * per));
      volumeLo_.push_back(vol.lo), volumeHi_.push_back(vol.hi);
      lo = glm::min(lo, vol.lo), hi = glm::max(hi, vol.hi);
      solidVoxels_ += vol.solidVoxels;
      warnings_.insert(warnings_.end(), vol.warnings.begin(), vol.warnings.end());
    }
    if (!f.quiet())
      for (const std::string& w : warnings_)
        std::fprintf(stderr, "diffrender: warning: %s\n", w.c_str());
    volumeSize_ = n;
    const int depth = n.z * int(inserted.size());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // Mips as far as each grid's slab of the stack stays whole along z (eq. 6's cones filter
    // within one mesh's grid) and every side keeps a texel.
    objectLevels_ = 1;
    while (objectLevels_ < 8 && n.z % (1 << objectLevels_) == 0 &&
           std::min({n.x, n.y, n.z}) >> objectLevels_ > 0)
      ++objectLevels_;
    occupancy_ = gl::Texture::volume(GL_R8, n.x, n.y, depth, objectLevels_);
    glTextureSubImage3D(occupancy_.id(), 0, 0, 0, 0, n.x, n.y, depth, GL_RED, GL_UNSIGNED_BYTE,
                        occupancy.data());
    if (params_.query == DiffrenderParameters::Query::Vct) {
      glGenerateTextureMipmap(occupancy_.id());
      occupancy_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
      objectLight_ = gl::Texture::volume(GL_RGBA16F, n.x, n.y, depth, objectLevels_);
      objectLight_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
      for (const gl::Texture* t : {&occupancy_, &objectLight_})
        for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
          glTextureParameteri(t->id(), w, GL_CLAMP_TO_EDGE);
      objectLightProgram_ =
          gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/object_light.comp"}});
    }
    surface_ = gl::Texture::volume(GL_RGBA8, n.x, n.y, depth);
    glTextureSubImage3D(surface_.id(), 0, 0, 0, 0, n.x, n.y, depth, GL_RGBA, GL_UNSIGNED_BYTE,
                        surface.data());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    // The impostor's centre: the middle of all inserted meshes' boxes, or where the scene puts it.
    centre_ = params_.impostorCentre ? f.scene().local(*params_.impostorCentre) : 0.5f * (lo + hi);
    // The farthest corner of the scene's bounds from the centre: DIT's search ends there.
    reach_ = 0;
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 corner((c & 1) ? f.boundsHi().x : f.boundsLo().x,
                             (c & 2) ? f.boundsHi().y : f.boundsLo().y,
                             (c & 4) ? f.boundsHi().z : f.boundsLo().z);
      reach_ = std::max(reach_, glm::length(corner - centre_));
    }
    reach_ = std::max(reach_ * 1.01f, 1e-3f);
  }

  // The six faces of the captured scene as seen from the objects' centre: the lights' cut (the
  // whole scan at about a shadow map's resolution) and the captured scene's meshes, with their
  // distances; then the gaps and the environment filled in and the mips made.
  void renderImpostor(SceneFrame& f) {
    if (builtCut_ == f.cutGeneration() && builtEnv_ == f.environmentGeneration()) return;
    builtCut_ = f.cutGeneration(), builtEnv_ = f.environmentGeneration();
    impostorBuilds_++;
    const int S = params_.impostorSize;
    static const std::array<glm::vec3, 6> dirs = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                                  glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                                  glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
    static const std::array<glm::vec3, 6> ups = {glm::vec3(0, -1, 0), glm::vec3(0, -1, 0),
                                                 glm::vec3(0, 0, 1),  glm::vec3(0, 0, -1),
                                                 glm::vec3(0, -1, 0), glm::vec3(0, -1, 0)};
    const glm::vec3 extent = f.boundsHi() - f.boundsLo();
    const float far = 4.0f * std::max(glm::length(extent), 1e-3f) +
                      glm::length(centre_ - 0.5f * (f.boundsLo() + f.boundsHi()));
    const float near = std::max(far * 1e-6f, 1e-4f);
    const glm::mat4 clipFromView = glm::perspective(glm::radians(90.0f), 1.0f, near, far);
    beginDepthDraw(S);
    f.bindSceneBuffers();
    for (int face = 0; face < 6; ++face) {
      impostorFbo_.attachLayer(GL_COLOR_ATTACHMENT0, raw_, face);
      impostorFbo_.attach(GL_DEPTH_ATTACHMENT, rawDepth_);
      if (face == 0) impostorFbo_.finish(1, "diffrender distance impostor");
      glBindFramebuffer(GL_FRAMEBUFFER, impostorFbo_.id());
      const float zero[4] = {0, 0, 0, 0}, one = 1.0f;
      glClearBufferfv(GL_COLOR, 0, zero);
      glClearBufferfv(GL_DEPTH, 0, &one);
      const glm::mat4 viewFromWorld =
          glm::lookAt(centre_, centre_ + dirs[size_t(face)], ups[size_t(face)]);
      const glm::mat4 clip = clipFromView * viewFromWorld;
      // A 90-degree face: S / 2 texels per unit at distance 1.
      impostorScan_.use();
      glUniform1f(impostorScan_.uniform("uFaceSize"), float(S));
      glUniform1f(impostorScan_.uniform("uNear"), near);
      glUniform1f(impostorScan_.uniform("uFar"), far);
      f.drawScans(impostorScan_, clip, viewFromWorld, 0.5f * float(S), false, true);
      impostorMesh_.use();
      glUniform3fv(impostorMesh_.uniform("uCentre"), 1, &centre_[0]);
      f.drawMeshesWhere(impostorMesh_, clip, true, [this](size_t i) {
        return i >= insertedMesh_.size() || !insertedMesh_[i];
      });
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    const GLuint groups = GLuint((S + 7) / 8);
    pull_.use();
    glBindTextureUnit(0, raw_.id());
    glBindImageTexture(0, colourSum_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, distanceSum_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
    glUniform1i(pull_.uniform("uSize"), S);
    glDispatchCompute(groups, groups, 6);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    GL_TEXTURE_UPDATE_BARRIER_BIT);
    glGenerateTextureMipmap(colourSum_.id());
    glGenerateTextureMipmap(distanceSum_.id());
    fill_.use();
    f.bindEnvironment(fill_);
    glBindTextureUnit(0, raw_.id());
    glBindTextureUnit(1, colourSum_.id());
    glBindTextureUnit(2, distanceSum_.id());
    glBindImageTexture(0, impostor_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform1i(fill_.uniform("uSize"), S);
    glUniform1i(fill_.uniform("uFillLevels"), kFillLevels);
    glDispatchCompute(groups, groups, 6);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    glGenerateTextureMipmap(impostor_.id());
  }

  // The voxel cone tracer's scene volume over the scene's bounds: cubic voxels, `scene_voxels`
  // along the longest side; R11G11B10F radiance (premultiplied) and R8 opacity with their mips
  // (5 bytes a voxel, 8/7 with the mips), and from level 1 on RGBA8 opacity per axis (4 bytes
  // an eighth of the voxels, 8/7 with its mips): 256^3 is 105 MB, under one 128 MiB range.
  void setUpSceneVolume() {
    const glm::vec3 lo = sceneLo_, extent = sceneHi_ - sceneLo_;
    const float longest = std::max({extent.x, extent.y, extent.z, 1e-3f});
    // A voxel of margin on every side (a closed room's walls lie on the bounds, and a wall in the
    // border voxels is half blended with the empty border at every level), and every side a
    // multiple of 2^kSceneMips: a mip of an odd size drops its last layer, and with it the
    // ceiling of a room from every level coarser than the first (a third of the upward cones
    // then saw the sky). The coarsest level is 2^kSceneMips voxels wide.
    constexpr int kSceneMips = 5;
    const int step = 1 << kSceneMips;
    sceneCell_ = longest / float(std::max(params_.sceneVoxels - 3, 1));
    const glm::ivec3 need = glm::ivec3(glm::ceil(extent / sceneCell_)) + 3;
    sceneDims_ = (glm::max(need, glm::ivec3(1)) + (step - 1)) / step * step;
    sceneOrigin_ = lo - glm::vec3(sceneCell_);
    const double bytes =
        double(sceneDims_.x) * sceneDims_.y * sceneDims_.z * (5.0 + 4.0 / 8.0) * 8.0 / 7.0;
    if (bytes > double(128 << 20))
      throw Error(sceneFile_, "scene.gi.parameters.scene_voxels",
                  "the scene volume would take " + std::to_string(int(bytes / 1e6)) +
                      " MB, over the 128 MiB bound: use fewer voxels");
    const int levels = kSceneMips + 1;
    sceneLevels_ = levels;
    sceneRadiance_ =
        gl::Texture::volume(GL_R11F_G11F_B10F, sceneDims_.x, sceneDims_.y, sceneDims_.z, levels);
    sceneOpacity_ = gl::Texture::volume(GL_R8, sceneDims_.x, sceneDims_.y, sceneDims_.z, levels);
    const glm::ivec3 half = sceneDims_ / 2;
    sceneOpacityDir_ = gl::Texture::volume(GL_RGBA8, half.x, half.y, half.z, levels - 1);
    for (const gl::Texture* t : {&sceneRadiance_, &sceneOpacity_, &sceneOpacityDir_}) {
      t->setFilter(t == &sceneOpacityDir_ ? GL_NEAREST_MIPMAP_LINEAR : GL_LINEAR_MIPMAP_LINEAR,
                   t == &sceneOpacityDir_ ? GL_NEAREST : GL_LINEAR);
      for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        glTextureParameteri(t->id(), w, GL_CLAMP_TO_BORDER);
    }
    // The fixed-point sums hold a slab of z layers at a time, within one 128 MiB range.
    const size_t layer = size_t(sceneDims_.x) * size_t(sceneDims_.y) * 16;
    slabDepth_ = std::clamp(int(size_t(128 << 20) / layer), 1, sceneDims_.z);
    for (gl::Texture& t : sums_)
      t = gl::Texture::volume(GL_R32UI, sceneDims_.x, sceneDims_.y, slabDepth_);
    voxelize_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "points/points.vert"},
                                   {GL_FRAGMENT_SHADER, "gi/diffrender/scene_voxelize.frag"}},
                                  {{"NL_SCENE_FRAME", "1"}});
    resolve_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/scene_resolve.comp"}});
    opacityMip_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/diffrender/scene_opacity_mip.comp"}});
    sceneFbo_ = gl::Framebuffer::create();
    glNamedFramebufferParameteri(sceneFbo_.id(), GL_FRAMEBUFFER_DEFAULT_WIDTH, sceneDims_.x);
    glNamedFramebufferParameteri(sceneFbo_.id(), GL_FRAMEBUFFER_DEFAULT_HEIGHT, sceneDims_.y);
  }

  // The lights' cut voxelised (when the cut changes): slab by slab, each point one pixel of an
  // orthographic view down z whose fragment adds it to its voxel, then the slab resolved.
  void buildSceneVolume(SceneFrame& f) {
    if (sceneBuiltCut_ == f.cutGeneration()) return;
    sceneBuiltCut_ = f.cutGeneration();
    constexpr float kFixedPoint = 1024.0f;
    // The view reaches a voxel past the volume on every side: a point on its edge (a wall on the
    // scene's bounds) sits on the first pixel's edge, which rasterisation may leave uncovered
    // (the fragment finds its voxel from the point's position, not from the pixel).
    const glm::vec3 hi = sceneOrigin_ + glm::vec3(sceneDims_) * sceneCell_;
    const glm::mat4 clip =
        glm::ortho(sceneOrigin_.x - sceneCell_, hi.x + sceneCell_, sceneOrigin_.y - sceneCell_,
                   hi.y + sceneCell_, -(hi.z + sceneCell_), -(sceneOrigin_.z - sceneCell_));
    glBindFramebuffer(GL_FRAMEBUFFER, sceneFbo_.id());
    glViewport(0, 0, sceneDims_.x, sceneDims_.y);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glEnable(GL_PROGRAM_POINT_SIZE);
    const GLuint zero = 0;
    for (int first = 0; first < sceneDims_.z; first += slabDepth_) {
      for (gl::Texture& t : sums_)
        glClearTexImage(t.id(), 0, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
      for (int k = 0; k < 4; ++k)
        glBindImageTexture(GLuint(k), sums_[size_t(k)].id(), 0, GL_TRUE, 0, GL_READ_WRITE,
                           GL_R32UI);
      voxelize_.use();
      glUniform3fv(voxelize_.uniform("uVolumeOrigin"), 1, &sceneOrigin_[0]);
      glUniform1f(voxelize_.uniform("uCell"), sceneCell_);
      glUniform3i(voxelize_.uniform("uDims"), sceneDims_.x, sceneDims_.y, sceneDims_.z);
      glUniform1i(voxelize_.uniform("uSlabFirst"), first);
      glUniform1i(voxelize_.uniform("uSlabDepth"), slabDepth_);
      glUniform1f(voxelize_.uniform("uFixedPoint"), kFixedPoint);
      // One-pixel points: the fragment stage runs once per point.
      f.drawScans(voxelize_, clip, glm::mat4(1.0f), 1e-9f, true, true);
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
      resolve_.use();
      for (int k = 0; k < 4; ++k)
        glBindImageTexture(GLuint(k), sums_[size_t(k)].id(), 0, GL_TRUE, 0, GL_READ_ONLY, GL_R32UI);
      glBindImageTexture(4, sceneRadiance_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R11F_G11F_B10F);
      glBindImageTexture(5, sceneOpacity_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R8);
      glUniform3i(resolve_.uniform("uDims"), sceneDims_.x, sceneDims_.y, sceneDims_.z);
      glUniform1i(resolve_.uniform("uSlabFirst"), first);
      glUniform1i(resolve_.uniform("uSlabDepth"), slabDepth_);
      glUniform1f(resolve_.uniform("uFixedPoint"), kFixedPoint);
      glDispatchCompute(GLuint((sceneDims_.x + 3) / 4), GLuint((sceneDims_.y + 3) / 4),
                        GLuint((slabDepth_ + 3) / 4));
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                      GL_TEXTURE_UPDATE_BARRIER_BIT);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glGenerateTextureMipmap(sceneRadiance_.id());
    glGenerateTextureMipmap(sceneOpacity_.id());
    buildDirectionalOpacity();
  }

  // Level by level from the base opacity: the directional texture's level k is the volume's k + 1.
  void buildDirectionalOpacity() {
    opacityMip_.use();
    glBindImageTexture(1, sceneOpacity_.id(), 0, GL_TRUE, 0, GL_READ_ONLY, GL_R8);
    for (int k = 0; k + 1 < sceneLevels_; ++k) {
      const glm::ivec3 src = sceneDims_ >> k, dst = sceneDims_ >> (k + 1);
      glBindImageTexture(0, sceneOpacityDir_.id(), k, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA8);
      glBindImageTexture(2, sceneOpacityDir_.id(), std::max(k - 1, 0), GL_TRUE, 0, GL_READ_ONLY,
                         GL_RGBA8);
      glUniform3i(opacityMip_.uniform("uDims"), dst.x, dst.y, dst.z);
      glUniform3i(opacityMip_.uniform("uSourceDims"), src.x, src.y, src.z);
      glUniform1i(opacityMip_.uniform("uFromBase"), k == 0 ? 1 : 0);
      glDispatchCompute(GLuint((dst.x + 3) / 4), GLuint((dst.y + 3) / 4), GLuint((dst.z + 3) / 4));
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    }
  }

  // The lights' shadow maps as the frame draws them (the same views, resolution and offsets) but
  // without the inserted meshes: the visibility the capture was lit with.
  void renderShadowsWithout(SceneFrame& f) {
    const std::vector<glm::mat4>& views = f.lightClipFromWorld();
    const int S = f.frameParameters().shadowMapSize;
    const int layers = std::max<int>(int(views.size()), 1);
    if (shadowWithout_.width() != S || shadowLayers_ != layers) {
      shadowWithout_ = gl::Texture::array2d(GL_DEPTH_COMPONENT32F, S, S, layers);
      shadowWithout_.setFilter(GL_LINEAR, GL_LINEAR);
      shadowWithout_.setDepthCompare(true);
      shadowLayers_ = layers;
    }
    beginDepthDraw(S);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.5f, 2.0f);
    for (size_t layer = 0; layer < size_t(layers); ++layer) {
      shadowFbo_.attachLayer(GL_DEPTH_ATTACHMENT, shadowWithout_, int(layer));
      if (layer == 0) shadowFbo_.finish(0, "diffrender shadow maps");
      glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo_.id());
      const float one = 1.0f;
      glClearBufferfv(GL_DEPTH, 0, &one);
      if (layer >= views.size()) continue;
      f.drawMeshesWhere(meshShadow_, views[layer], false, [this](size_t i) {
        return i >= insertedMesh_.size() || !insertedMesh_[i];
      });
      const frame::LightRecord* owner = nullptr;
      for (const auto& r : f.lights())
        if (size_t(r.shadow.x) <= layer) owner = &r;
      if (!owner) continue;
      const bool ortho = int(owner->position.w) == NL_LIGHT_DIRECTIONAL;
      f.drawScans(scanShadow_, views[layer], f.lightViewFromWorld()[layer], 1.0f / owner->shadow.y,
                  ortho, true);
    }
    glDisable(GL_POLYGON_OFFSET_FILL);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  void bindCommon(SceneFrame& f, const gl::ShaderProgram& p) {
    f.bindSceneBuffers();
    p.use();
    f.bindEnvironment(p);
    glBindTextureUnit(DR_UNIT_IMPOSTOR, impostor_.id());
    glBindTextureUnit(DR_UNIT_OCCUPANCY, occupancy_.id());
    glBindTextureUnit(DR_UNIT_SURFACE, surface_.id());
    stats_.bindBase(GL_SHADER_STORAGE_BUFFER, DR_SSBO_STATS);
    glUniform3fv(p.uniform("uImpostorCentre"), 1, &centre_[0]);
    glUniform1i(p.uniform("uImpostorSize"), params_.impostorSize);
    glUniform1i(p.uniform("uImpostorLevels"), impostorLevels_);
    glUniform1f(p.uniform("uImpostorReach"), reach_);
    using Q = DiffrenderParameters::Query;
    const int query = params_.query == Q::Em      ? DR_QUERY_EM
                      : params_.query == Q::Vct   ? DR_QUERY_VCT
                      : params_.query == Q::Exact ? DR_QUERY_EXACT
                                                  : DR_QUERY_DIT;
    glUniform1i(p.uniform("uQuery"), query);
    glUniform1i(p.uniform("uTopCount"), GLint(hier_.topCount()));
    glUniform1i(p.uniform("uMeshBvhNodes"), tracesExactly() ? meshBvhNodes_ : 0);
    glUniform1i(p.uniform("uCompareExact"), params_.compareExact ? 1 : 0);
    if (tracesExactly()) {
      hier_.top().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TOP);
      hier_.nodes().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
      hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
      meshBvh_.bindBase(GL_SHADER_STORAGE_BUFFER, DR_SSBO_MESH_BVH);
      meshTriangles_.bindBase(GL_SHADER_STORAGE_BUFFER, DR_SSBO_MESH_TRIANGLES);
    }
    if (params_.query == DiffrenderParameters::Query::Vct) {
      glBindTextureUnit(DR_UNIT_SCENE_RADIANCE, sceneRadiance_.id());
      glBindTextureUnit(DR_UNIT_SCENE_OPACITY, sceneOpacity_.id());
      glBindTextureUnit(DR_UNIT_SCENE_OPACITY_DIR, sceneOpacityDir_.id());
      glBindTextureUnit(DR_UNIT_OBJECT_LIGHT, objectLight_.id());
    }
    glUniform1i(p.uniform("uObjectLevels"), objectLevels_);
    glUniform3fv(p.uniform("uSceneOrigin"), 1, &sceneOrigin_[0]);
    glUniform1f(p.uniform("uSceneCell"), sceneCell_);
    glUniform3i(p.uniform("uSceneDims"), sceneDims_.x, sceneDims_.y, sceneDims_.z);
    glUniform1i(p.uniform("uSceneLevels"), sceneLevels_);
    glUniform1i(p.uniform("uDitIterations"), params_.ditIterations);
    glUniform1i(p.uniform("uVolumeCount"), GLint(volumeLo_.size()));
    glUniform3fv(p.uniform("uVolumeLo"), GLsizei(volumeLo_.size()), &volumeLo_[0][0]);
    glUniform3fv(p.uniform("uVolumeHi"), GLsizei(volumeHi_.size()), &volumeHi_[0][0]);
    glUniform3i(p.uniform("uVolumeSize"), volumeSize_.x, volumeSize_.y, volumeSize_.z);
    glUniform1ui(p.uniform("uSeed"), seed_);
    glUniform1i(p.uniform("uScale"), params_.deltaScale);
  }

  void shade(SceneFrame& f, const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const int s = params_.deltaScale;
    const int lw = (tile.width + s - 1) / s, lh = (tile.height + s - 1) / s;
    if (deltaLow_.width() != lw || deltaLow_.height() != lh) {
      deltaLow_ = gl::Texture(GL_RGBA32F, lw, lh);
      guideLow_ = gl::Texture(GL_RGBA32F, lw, lh);
      rhoLow_ = gl::Texture(GL_RGBA32F, lw, lh);
    }
    if (mask_.width() != tile.width || mask_.height() != tile.height)
      mask_ = gl::Texture(GL_R32F, tile.width, tile.height);
    const GLbitfield barriers = GL_SHADER_STORAGE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                                GL_TEXTURE_FETCH_BARRIER_BIT;
    ctx.bindTexture("depth", 0);
    ctx.bindTexture("base_colour", 1);
    ctx.bindTexture("normal", 2);
    ctx.bindTexture("material", 3);
    glBindTextureUnit(DR_UNIT_DIRECT, ctx.target("radiance").id());
    const gl::Texture& maps = ctx.target("shadow_maps");
    maps.setFilter(GL_LINEAR, GL_LINEAR);
    maps.setDepthCompare(true);
    glBindTextureUnit(4, maps.id());
    glBindTextureUnit(DR_UNIT_SHADOW_WITHOUT, shadowWithout_.id());
    if (params_.query == DiffrenderParameters::Query::Vct && objectLightStale_) {
      objectLightStale_ = false;
      lightObjectVolume(f);
    }
    bindCommon(f, delta_);
    glUniform1i(delta_.uniform("uSamples"), params_.samples);
    glUniform1i(delta_.uniform("uCache"), params_.cache);
    glUniform1i(delta_.uniform("uEstimateMaterial"), params_.materialEstimate ? 1 : 0);
    glUniform1f(delta_.uniform("uRhoMax"), params_.rhoMax);
    glBindImageTexture(0, deltaLow_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, guideLow_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(2, rhoLow_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glDispatchCompute(GLuint((lw + 7) / 8), GLuint((lh + 7) / 8), 1);
    glMemoryBarrier(barriers);
    bindCommon(f, compose_);
    glBindTextureUnit(DR_UNIT_DELTA, deltaLow_.id());
    glBindTextureUnit(DR_UNIT_GUIDE, guideLow_.id());
    glUniform1i(compose_.uniform("uObjectSamples"), params_.objectSamples);
    glUniform1i(compose_.uniform("uSelfShadow"), params_.selfShadow ? 1 : 0);
    glUniform1f(compose_.uniform("uAmbient"), params_.ambient);
    glUniform1i(compose_.uniform("uSecondaryBounce"), params_.secondaryBounce ? 1 : 0);
    const bool photo = !params_.background.empty();
    if (photo && (background_.width() != tile.fullWidth || background_.height() != tile.fullHeight))
      throw Error(backgroundFile_, "scene.gi.parameters.background",
                  params_.background + " is " + std::to_string(background_.width()) + "x" +
                      std::to_string(background_.height()) + ", the image " +
                      std::to_string(tile.fullWidth) + "x" + std::to_string(tile.fullHeight) +
                      ": the photograph must be the camera's view at its resolution");
    glUniform1i(compose_.uniform("uHasBackground"), photo ? 1 : 0);
    if (photo) glBindTextureUnit(DR_UNIT_BACKGROUND, background_.id());
    const glm::mat3 toScan = params_.backgroundMap, toPhoto = glm::inverse(params_.backgroundMap);
    glUniformMatrix3fv(compose_.uniform("uPhotoToScan"), 1, GL_FALSE, &toScan[0][0]);
    glUniformMatrix3fv(compose_.uniform("uScanToPhoto"), 1, GL_FALSE, &toPhoto[0][0]);
    glUniform1f(compose_.uniform("uDeltaGain"), 1.0f);
    glBindImageTexture(0, ctx.target("radiance_diffrender").id(), 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    glBindImageTexture(1, mask_.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glDispatchCompute(GLuint((tile.width + 7) / 8), GLuint((tile.height + 7) / 8), 1);
    glMemoryBarrier(barriers | GL_FRAMEBUFFER_BARRIER_BIT);
    if (!params_.aovs.empty()) keepAovs(tile, lw, lh);
  }

  // Eq. 6's object light: every boundary voxel lit (object_light.comp), then the mips.
  void lightObjectVolume(SceneFrame& f) {
    bindCommon(f, objectLightProgram_);
    const int depth = volumeSize_.z * int(volumeLo_.size());
    glBindImageTexture(0, objectLight_.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA16F);
    glDispatchCompute(GLuint((volumeSize_.x + 3) / 4), GLuint((volumeSize_.y + 3) / 4),
                      GLuint((depth + 3) / 4));
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    glGenerateTextureMipmap(objectLight_.id());
  }

  // The tile's AOVs into the full image's (GL rows bottom up; the images' top down).
  void keepAovs(const frame::Tile& tile, int lw, int lh) {
    const int s = params_.deltaScale;
    const int fw = (tile.fullWidth + s - 1) / s, fh = (tile.fullHeight + s - 1) / s;
    if (aovDelta_.width != fw || aovDelta_.height != fh) {
      aovDelta_ = HdrImage(fw, fh), aovRho_ = HdrImage(fw, fh);
    }
    if (aovMask_.width != tile.fullWidth || aovMask_.height != tile.fullHeight)
      aovMask_ = HdrImage(tile.fullWidth, tile.fullHeight);
    std::vector<float> delta(size_t(lw) * size_t(lh) * 4), rho(delta.size()),
        mask(size_t(tile.width) * size_t(tile.height));
    glGetTextureImage(deltaLow_.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(delta.size() * 4),
                      delta.data());
    glGetTextureImage(rhoLow_.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(rho.size() * 4), rho.data());
    glGetTextureImage(mask_.id(), 0, GL_RED, GL_FLOAT, GLsizei(mask.size() * 4), mask.data());
    for (int y = 0; y < lh; ++y)
      for (int x = 0; x < lw; ++x) {
        const int gx = tile.x0 / s + x, gy = tile.y0 / s + y;
        if (gx >= fw || gy >= fh) continue;
        const float* d = &delta[(size_t(y) * size_t(lw) + size_t(x)) * 4];
        const float* r = &rho[(size_t(y) * size_t(lw) + size_t(x)) * 4];
        aovDelta_.set(gx, fh - 1 - gy, Rgb(d[0], d[1], d[2]));
        aovRho_.set(gx, fh - 1 - gy, Rgb(r[0], r[1], r[2]));
      }
    for (int y = 0; y < tile.height; ++y)
      for (int x = 0; x < tile.width; ++x) {
        const float m = mask[size_t(y) * size_t(tile.width) + size_t(x)];
        aovMask_.set(tile.x0 + x, tile.fullHeight - 1 - (tile.y0 + y), Rgb(m));
      }
  }

  DiffrenderParameters params_;
  uint32_t seed_ = 1;
  std::vector<bool> insertedMesh_;
  std::vector<std::string> warnings_;
  uint64_t solidVoxels_ = 0, impostorBuilds_ = 0;
  uint64_t builtCut_ = ~0ull, builtEnv_ = ~0ull;
  std::vector<glm::vec3> volumeLo_, volumeHi_;  // each inserted mesh's grid's box
  glm::vec3 centre_{0.0f};
  glm::ivec3 volumeSize_{1};
  int impostorLevels_ = 1;
  float reach_ = 1;
  gl::Texture colourSum_, distanceSum_;  // the pull-push's coverage-weighted sums and their mips
  gl::Texture raw_, rawDepth_, impostor_, occupancy_, surface_, deltaLow_, guideLow_, rhoLow_,
      mask_;
  HdrImage aovDelta_, aovRho_, aovMask_;
  gl::Texture background_;
  std::string backgroundFile_;
  // vct's scene volume and its fixed-point sums (one slab of z layers at a time).
  gl::Texture sceneRadiance_, sceneOpacity_, sceneOpacityDir_;
  std::array<gl::Texture, 4> sums_;
  gl::ShaderProgram voxelize_, resolve_, opacityMip_;
  gl::Framebuffer sceneFbo_;
  glm::vec3 sceneLo_{0.0f}, sceneHi_{1.0f}, sceneOrigin_{0.0f};
  float sceneCell_ = 1;
  glm::ivec3 sceneDims_{1};
  int sceneLevels_ = 1;
  int slabDepth_ = 1;
  uint64_t sceneBuiltCut_ = ~0ull;
  // vct: the boundary voxels' light for eq. 6's cones, lit once a frame (before the first tile).
  gl::Texture objectLight_;
  gl::ShaderProgram objectLightProgram_;
  int objectLevels_ = 1;
  bool objectLightStale_ = true;
  std::string sceneFile_;
  // exact's hierarchies of the lights' cut.
  size_t layer_ = 0;
  CutHierarchies hier_;
  gl::Buffer meshBvh_, meshTriangles_;  // the captured meshes' triangle BVH
  GLint meshBvhNodes_ = 0;
  uint64_t hierCut_ = ~0ull;
  gl::Texture shadowWithout_;
  int shadowLayers_ = 0;
  gl::Framebuffer impostorFbo_, shadowFbo_;
  gl::ShaderProgram impostorScan_, impostorMesh_, pull_, fill_, delta_, compose_, meshShadow_,
      scanShadow_;
  gl::Buffer stats_;
};

}  // namespace

std::unique_ptr<Method> createDiffrenderMethod(const Scene& scene, const MethodContext& ctx) {
  // Parsed once: the drawn scene (a capture layer in place of the colour) and the extension.
  DiffrenderParameters params = diffrenderParameters(scene);
  const Scene drawn = diffrenderCaptureScene(scene, params);
  return createRasterMethod(drawn, ctx,
                            std::make_unique<DiffrenderExtension>(drawn, std::move(params)));
}

}  // namespace nestlight::gi
