// The GI frame's meshes (read from their files, placed in the scene's local frame, uploaded
// and drawn with shaders/gi/raster/mesh.vert) and the scene's materials (NL_SSBO_MATERIALS).
#include <cmath>

#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

void RasterMethod::loadMeshes() {
  for (const auto& m : scene_.meshes) {
    cpuMeshes_.push_back(readMesh(m.path.string()));
    const TriangleMesh& mesh = cpuMeshes_.back();
    const glm::mat4 localFromObject = scene_.localFromObject(m);
    const glm::mat3 normalFrom = glm::transpose(glm::inverse(glm::mat3(localFromObject)));
    std::vector<float> v;
    v.reserve(mesh.positions.size() * 9);
    LocalBox object;
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      const glm::vec3 p = glm::vec3(localFromObject * glm::vec4(mesh.positions[i], 1.0f));
      glm::vec3 n(0.0f);
      if (!mesh.normals.empty()) {
        n = normalFrom * mesh.normals[i];
        const float len = glm::length(n);
        n = len > 0 && std::isfinite(len) ? n / len : glm::vec3(0.0f);
      }
      const Rgb c = mesh.colors.empty() ? Rgb(1.0f) : mesh.colors[i];
      v.insert(v.end(), {p.x, p.y, p.z, n.x, n.y, n.z, c.r, c.g, c.b});
      if (std::isfinite(p.x + p.y + p.z)) bounds_.add(p), object.add(p);
    }
    if (!object.empty()) objectBounds_.push_back(object);
    GpuMesh g;
    g.vertices = gl::Buffer(v.size() * 4, v.data(), 0);
    g.indices = gl::Buffer(mesh.indices.size() * 4, mesh.indices.data(), 0);
    g.indexCount = GLsizei(mesh.indices.size());
    g.material = m.material;
    g.vao = gl::VertexArray::create();
    const GLuint vao = g.vao.id();
    glVertexArrayVertexBuffer(vao, 0, g.vertices.id(), 0, 9 * sizeof(float));
    glVertexArrayElementBuffer(vao, g.indices.id());
    for (GLuint a = 0; a < 3; ++a) {
      glEnableVertexArrayAttrib(vao, a);
      glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
      glVertexArrayAttribBinding(vao, a, 0);
    }
    meshes_.push_back(std::move(g));
  }
  if (bounds_.empty()) bounds_.add(glm::vec3(0.0f));
}

void RasterMethod::uploadMaterials() {
  std::vector<frame::MaterialRecord> recs;
  for (const Material& m : scene_.materials) {
    frame::MaterialRecord r{};
    const int type = m.type == MaterialType::Lambert ? NL_MATERIAL_LAMBERT
                     : m.type == MaterialType::GGX   ? NL_MATERIAL_GGX
                                                     : NL_MATERIAL_PRINCIPLED;
    r.baseColor = glm::vec4(m.baseColor.r, m.baseColor.g, m.baseColor.b, float(type));
    r.params = glm::vec4(m.roughness, m.metallic, m.specular, m.specularTint);
    r.params2 = glm::vec4(m.sheen, m.sheenTint, m.clearcoat, m.clearcoatGloss);
    r.emission = glm::vec4(m.emission.r, m.emission.g, m.emission.b, 0.0f);
    recs.push_back(r);
  }
  if (recs.empty()) recs.emplace_back();
  materialsBuffer_ = gl::Buffer(recs.size() * sizeof(frame::MaterialRecord), recs.data(), 0);
}

void RasterMethod::drawMeshes(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                              bool materials) {
  drawMeshesWhere(program, clipFromWorld, materials, [](size_t) { return true; });
}

void RasterMethod::drawMeshesWhere(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                                   bool materials, const std::function<bool(size_t)>& include) {
  program.use();
  glUniformMatrix4fv(program.uniform("uClipFromWorld"), 1, GL_FALSE, &clipFromWorld[0][0]);
  for (size_t i = 0; i < meshes_.size(); ++i) {
    if (!include(i)) continue;
    const GpuMesh& m = meshes_[i];
    if (materials) {
      const Material& mat = scene_.materials.at(m.material);
      glUniform3f(program.uniform("uBaseColor"), mat.baseColor.r, mat.baseColor.g, mat.baseColor.b);
      glUniform1i(program.uniform("uMaterialType"),
                  mat.type == MaterialType::Lambert ? NL_MATERIAL_LAMBERT
                  : mat.type == MaterialType::GGX   ? NL_MATERIAL_GGX
                                                    : NL_MATERIAL_PRINCIPLED);
      glUniform1f(program.uniform("uRoughness"), mat.roughness);
      glUniform1f(program.uniform("uMetallic"), mat.metallic);
      glUniform1ui(program.uniform("uMaterialIndex"), m.material);
    }
    glBindVertexArray(m.vao.id());
    glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
  }
}

}  // namespace nestlight::gi::frame_detail
