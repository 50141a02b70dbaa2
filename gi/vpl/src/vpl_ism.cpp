// Imperfect shadow maps: Ritschel, Grosch, Kim, Seidel, Dachsbacher and Kautz 2008, "Imperfect
// Shadow Maps for Efficient Computation of Indirect Illumination", with parabolic projection, on
// the resident cut's points as Preiner, "Real-Time Global Illumination in Point Clouds", draws
// them.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gi/mesh.h"
#include "vpl_extension.h"

namespace nestlight::gi::vpl {

// The meshes' surfels join the ISM occluders (and the bounces' hit points) as nodes of their own.
void VplExtension::setUpSurfels(SceneFrame& f) {
  const Scene& scene = f.scene();
  for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
    const SceneMesh& m = scene.meshes[mi];
    const TriangleMesh& mesh = f.meshes().at(mi);
    SurfelOptions o;
    o.method = m.surfelMethod;
    o.count = m.surfelCount;
    o.material = m.material;
    const Material& mat = scene.materials.at(m.material);
    o.baseColor = mat.baseColor;
    Surfels s = sampleSurfels(mesh, scene.localFromObject(m), o);
    if (s.positions.empty()) continue;
    double area = 0;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = 0; i < s.positions.size(); ++i) {
      area += s.area[i];
      lo = glm::min(lo, s.positions[i]);
      hi = glm::max(hi, s.positions[i]);
    }
    const float spacing = float(std::sqrt(area / double(s.positions.size())));
    objectsLo_ = glm::min(objectsLo_, lo);
    objectsHi_ = glm::max(objectsHi_, hi);
    PoolNode n{};
    n.box = glm::vec4(0.5f * (lo + hi), 0.5f * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}));
    n.lod = glm::vec4(spacing, 1e30f, spacing, 0.0f);
    n.range = glm::ivec4(int(surfelPoints_.size()), int(s.positions.size()), 0, 0);
    surfelNodes_.push_back(n);
    for (size_t i = 0; i < s.positions.size(); ++i) {
      PoolPoint q{};
      q.position = glm::vec4(s.positions[i], 0.5f * spacing);
      const glm::vec3 nn = s.normals[i];
      float a = s.area[i];
      uint32_t areaBits;
      std::memcpy(&areaBits, &a, 4);
      q.surface =
          glm::uvec4(frame::packNormal(nn.x, nn.y, nn.z), packHalf2(s.albedo[i].r, s.albedo[i].g),
                     packHalf2(s.albedo[i].b, 0.0f) | (s.material[i] << 16), areaBits);
      surfelPoints_.push_back(q);
    }
  }
}

void VplExtension::setPoolUniforms(const gl::ShaderProgram& p) const {
  glUniform1i(p.uniform("uNodeCount"), int(poolNodeCount_));
  glUniform1i(p.uniform("uIsmSize"), params_.ismSize);
  glUniform1f(p.uniform("uLodScale"), params_.lodScale);
  glUniform1ui(p.uniform("uPointBudget"), GLuint(params_.ismPoints));
  if (pool_.bytes()) pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
  if (poolNodes_.bytes())
    poolNodes_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL_NODES, 0, poolNodes_.bytes());
}

// The ISM pool: the lights' cut's points (gathered on the GPU from the nodes' buffers) and the
// meshes' surfels, with a node table for the level-of-detail choice.
void VplExtension::buildPool(SceneFrame& f) {
  const auto& cut = f.lightsCut();
  std::vector<PoolNode> nodes;
  std::vector<char> hasChild(cut.size(), 0);
  for (const auto& c : cut)
    if (c.parent >= 0) hasChild[size_t(c.parent)] = 1;
  const size_t maxPoints = gl::kMaxSsboRange / sizeof(PoolPoint) - surfelPoints_.size();
  uint64_t points = 0, dropped = 0;
  std::vector<size_t> taken;
  for (size_t i = 0; i < cut.size(); ++i) {
    const CutNode& c = cut[i];
    if (c.numPoints == 0) continue;
    if (points + c.numPoints > maxPoints) {  // the finest nodes come last in the list
      dropped += c.numPoints;
      continue;
    }
    PoolNode n{};
    n.box = glm::vec4(c.origin + glm::vec3(0.5f * c.size), 0.5f * c.size);
    const float parentSpacing = c.parent >= 0 ? cut[size_t(c.parent)].spacing : 1e30f;
    n.lod = glm::vec4(c.spacing, parentSpacing, hasChild[i] ? 0.0f : c.spacing, 0.0f);
    n.range = glm::ivec4(int(points), int(c.numPoints), 0, 0);
    nodes.push_back(n);
    taken.push_back(i);
    points += c.numPoints;
  }
  const uint64_t scanPoints = points;
  scanPoints_ = scanPoints;
  emitSide_ = 1;
  while (uint64_t(emitSide_) * uint64_t(emitSide_) < scanPoints) emitSide_ *= 2;
  if (radianceCache_ && scanPoints > 0)
    emitPyramid_ = gl::Buffer(pyramidLayerFloats(emitSide_) * 4);
  for (PoolNode n : surfelNodes_) {
    n.range.x += int(scanPoints);
    nodes.push_back(n);
  }
  points += surfelPoints_.size();
  poolPoints_ = points;
  poolNote_ =
      dropped ? " (" + std::to_string(dropped) + " points of the finest nodes left out: 128 MiB)"
              : "";
  poolNodeCount_ = nodes.size();
  pool_ = points ? gl::Buffer(points * sizeof(PoolPoint)) : gl::Buffer();
  poolNodes_ =
      nodes.empty() ? gl::Buffer() : gl::Buffer(nodes.size() * sizeof(PoolNode), nodes.data(), 0);
  if (!surfelPoints_.empty())
    pool_.upload(surfelPoints_.data(), surfelPoints_.size() * sizeof(PoolPoint),
                 scanPoints * sizeof(PoolPoint));
  if (scanPoints == 0) return;
  pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
  gather_.use();
  const float splat = f.frameParameters().splatScale;
  int boundScan = -1;
  for (size_t j = 0; j < taken.size(); ++j) {
    const CutNode& c = cut[taken[j]];
    if (c.scan != boundScan) {
      f.bindLightsCutTree(boundScan = c.scan);
      f.bindScanClip(c.scan);
    }
    glUniform1i(gather_.uniform("uClipTest"), c.clipTest);
    glUniform1i(gather_.uniform("uNodeIndex"), c.indexInScan);
    glUniform1f(gather_.uniform("uNodeSize"), c.size);
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, c.buffer, 0,
                      GLsizeiptr(size_t(c.numPoints) * frame::kGpuPointBytes));
    glUniform3f(gather_.uniform("uNodeOrigin"), c.origin.x, c.origin.y, c.origin.z);
    glUniform1i(gather_.uniform("uFirst"), nodes[j].range.x);
    glUniform1ui(gather_.uniform("uNumPoints"), c.numPoints);
    glUniform1f(gather_.uniform("uRadius"), 0.5f * c.spacing * splat * 0.5f);
    glUniform1f(gather_.uniform("uColourScale"), c.colourScale);
    glUniform1i(gather_.uniform("uHdrColour"), c.hdrColour);
    glDispatchCompute((c.numPoints + 127) / 128, 1, 1);
  }
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
}

// The ISM atlas: every VPL's pool points splatted into its paraboloid map.
void VplExtension::addIsmPass(SceneFrame& f) {
  frame::FrameGraph& g = f.graph();
  g.addPass(
      "ism", frame::Scope::Frame,
      [](frame::PassBuilder& b) {
        b.read("vpls");
        b.write("ism_raw");
      },
      [this, &f](const frame::PassContext&) {
        bindCommon(f);
        const GLuint far = VPL_FAR_BITS;
        glClearNamedBufferData(ism_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &far);
        if (poolNodeCount_ == 0 || generationsRun_ == 0) return;
        ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
        splat_.use();
        setPoolUniforms(splat_);
        glUniform1i(splat_.uniform("uFirstVpl"), 0);
        glDispatchCompute(GLuint(params_.count * generationsRun_), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      });
}

}  // namespace nestlight::gi::vpl
