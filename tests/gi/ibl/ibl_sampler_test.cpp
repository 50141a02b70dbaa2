// The `ibl` method's samplers on the GPU against gi/core's densities: the environment's tabulated
// row and column CDFs (gi/ibl/environment_table.h, shaders/gi/ibl/ibl_environment.glsl) against
// EnvironmentMap::pdf, and the GLSL BSDF sampling (shaders/gi/common/brdf_sample.glsl) against
// pdfBsdf, by Pearson's chi-square over the sphere; the density each sample carries must be
// gi/core's at its direction. Also the meshes' BVH against brute force.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <memory>

#include "gi/chi2.h"
#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/ibl/environment_table.h"
#include "nestlight/gi/material.h"
#include "nestlight/gi/shared/triangle_bvh.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"

namespace nestlight::gi {
namespace {

using chi2::Chi2Options;
using chi2::Chi2Result;

// Runs shaders/tests/ibl_samplers.comp: `count` samples (xyz, pdf; pdf < 0: none).
class SamplerHarness {
 public:
  SamplerHarness()
      : ctx_(gl::createHeadlessContext()),
        program_({{GL_COMPUTE_SHADER, "tests/ibl_samplers.comp"}}) {}

  std::vector<glm::vec4> environment(const EnvironmentMap& map, size_t count, uint32_t seed) {
    const ibl::EnvironmentTable t = ibl::buildEnvironmentTable(map);
    gl::Buffer table(t.data.size() * 4, t.data.data(), 0);
    table.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_ENV);
    const HdrImage& img = map.image();
    const std::vector<float> rgba = img.rgba();
    gl::Texture tex(GL_RGBA32F, img.width, img.height);
    glTextureSubImage2D(tex.id(), 0, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT, rgba.data());
    glBindTextureUnit(5, tex.id());
    program_.use();
    glUniform1i(program_.uniform("uMode"), 0);
    glUniform1f(program_.uniform("uEnvRotation"), glm::radians(map.rotationDegrees()));
    glUniform1f(program_.uniform("uEnvScale"), map.scale());
    return run(count, seed);
  }

  std::vector<glm::vec4> bsdf(const Material& m, const glm::vec3& wo, size_t count, uint32_t seed) {
    gl::Buffer table(64);
    table.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_ENV);
    program_.use();
    glUniform1i(program_.uniform("uMode"), 1);
    const int type = m.type == MaterialType::Lambert ? NL_MATERIAL_LAMBERT
                     : m.type == MaterialType::GGX   ? NL_MATERIAL_GGX
                                                     : NL_MATERIAL_PRINCIPLED;
    glUniform1i(program_.uniform("uType"), type);
    glUniform3f(program_.uniform("uBase"), m.baseColor.r, m.baseColor.g, m.baseColor.b);
    glUniform4f(program_.uniform("uParams"), m.roughness, m.metallic, m.specular, m.specularTint);
    glUniform4f(program_.uniform("uParams2"), m.sheen, m.sheenTint, m.clearcoat, m.clearcoatGloss);
    glUniform3f(program_.uniform("uWo"), wo.x, wo.y, wo.z);
    return run(count, seed);
  }

 private:
  std::vector<glm::vec4> run(size_t count, uint32_t seed) {
    gl::Buffer out(count * sizeof(glm::vec4));
    out.bindBase(GL_SHADER_STORAGE_BUFFER, 0);
    glUniform1i(program_.uniform("uCount"), int(count));
    glUniform1ui(program_.uniform("uSeed"), seed);
    glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<glm::vec4> v(count);
    glGetNamedBufferSubData(out.id(), 0, GLsizeiptr(count * sizeof(glm::vec4)), v.data());
    return v;
  }

  std::unique_ptr<gl::GlContext> ctx_;
  gl::ShaderProgram program_;
};

// Feeds precomputed samples to chi2Test one by one.
Chi2Result chi2Of(const std::vector<glm::vec4>& s,
                  const std::function<double(const glm::vec3&)>& pdf, Chi2Options o) {
  size_t next = 0;
  o.samples = s.size();
  return chi2::chi2Test(
      [&](Rng&) -> std::optional<glm::vec3> {
        const glm::vec4 v = s[next++];
        if (v.w < 0) return std::nullopt;
        return glm::vec3(v);
      },
      pdf, o);
}

// A sky with a gradient, a bright sun and a black band, turned 30 degrees, half-scaled: the GPU's
// samples follow gi::EnvironmentMap's density, and each carries that density.
TEST(IblSamplers, EnvironmentCdfsMatchTheMapsDensityChiSquare) {
  SamplerHarness h;
  HdrImage img(32, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x)
      img.set(x, y, Rgb(0.1f + 0.05f * float(x % 7) + (y < 8 ? 0.5f : 0.0f)));
  for (int x = 0; x < 32; ++x) img.set(x, 11, Rgb(0.0f));
  img.set(20, 3, Rgb(2000.0f));
  const EnvironmentMap map(img, 30.0f, 0.5f);
  const std::vector<glm::vec4> s = h.environment(map, 1 << 20, 11);
  size_t mismatch = 0;
  for (const glm::vec4& v : s) {
    const float want = map.pdf(glm::vec3(v));
    // 1e-4 relative: the same density; a direction within float rounding of a texel edge may land
    // on its neighbour's value on one side only (a few in a million).
    if (!(std::abs(v.w - want) <= 1e-4f * want)) ++mismatch;
  }
  EXPECT_LT(mismatch, 20u) << "samples whose density differs from EnvironmentMap::pdf";
  Chi2Options o;
  const Chi2Result r = chi2Of(
      s, [&](const glm::vec3& d) { return double(map.pdf(d)); }, o);
  EXPECT_TRUE(r.passed) << r.message;
  EXPECT_EQ(r.failedSamples, 0u);
  EXPECT_NEAR(r.pdfIntegral, 1.0, 1e-4);
}

TEST(IblSamplers, BsdfSamplingMatchesGiCoresPdfChiSquare) {
  SamplerHarness h;
  struct Case {
    const char* name;
    Material m;
  };
  std::vector<Case> cases;
  Material lambert;
  lambert.baseColor = Rgb(0.6f);
  cases.push_back({"lambert", lambert});
  Material rough;
  rough.type = MaterialType::GGX, rough.baseColor = Rgb(0.8f, 0.5f, 0.2f), rough.roughness = 0.5f,
  rough.metallic = 0.3f;
  cases.push_back({"ggx r0.5 m0.3", rough});
  Material glossy = rough;
  glossy.roughness = 0.2f, glossy.metallic = 1;
  cases.push_back({"ggx r0.2 metal", glossy});
  Material coat;
  coat.type = MaterialType::Principled, coat.baseColor = Rgb(0.3f, 0.6f, 0.9f),
  coat.roughness = 0.4f, coat.sheen = 0.5f, coat.clearcoat = 1, coat.clearcoatGloss = 0.5f;
  cases.push_back({"principled clearcoat", coat});
  const float thetas[] = {0.3f, 1.2f};
  Chi2Options o;
  o.tests = int(cases.size() * std::size(thetas));
  uint32_t seed = 1;
  for (const Case& c : cases)
    for (float theta : thetas) {
      const glm::vec3 wo(std::sin(theta) * std::cos(0.7f), std::sin(theta) * std::sin(0.7f),
                         std::cos(theta));
      const std::vector<glm::vec4> s = h.bsdf(c.m, wo, 1 << 20, seed++);
      size_t mismatch = 0;
      for (const glm::vec4& v : s) {
        if (v.w < 0) continue;
        const float want = pdfBsdf(c.m, wo, glm::vec3(v));
        if (!(std::abs(v.w - want) <= 1e-3f * want)) ++mismatch;
      }
      // GPU transcendental functions are not the CPU's to the last ulp: 0.1% agreement, with a few
      // in a million on the lobes' steep flanks allowed.
      EXPECT_LT(mismatch, 50u) << c.name << " theta " << theta;
      const Chi2Result r = chi2Of(
          s, [&](const glm::vec3& d) { return double(pdfBsdf(c.m, wo, d)); }, o);
      EXPECT_TRUE(r.passed) << c.name << " theta " << theta << ": " << r.message;
    }
}

// The BVH's nearest hits are brute force's, over random triangles (degenerate ones among them,
// left out and counted) and random rays.
TEST(IblSamplers, TriangleBvhFindsTheNearestHit) {
  Rng rng(5);
  std::vector<glm::vec3> corners;
  for (int i = 0; i < 3000; ++i) {
    const glm::vec3 c = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 10.0f;
    for (int k = 0; k < 3; ++k)
      corners.push_back(c + glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5f);
  }
  for (int i = 0; i < 5; ++i)
    corners.insert(corners.end(), {glm::vec3(1.0f), glm::vec3(1.0f), glm::vec3(2.0f)});
  const TriangleBvh bvh = buildTriangleBvh(corners);
  EXPECT_EQ(bvh.degenerate, 5u);
  EXPECT_EQ(bvh.triangles.size(), 3000u);
  TriangleBvh brute;
  brute.triangles = bvh.triangles;
  brute.nodes.resize(1);
  brute.nodes[0].lo = glm::vec4(-1e30f, -1e30f, -1e30f, std::bit_cast<float>(0u | TRI_BVH_LEAF));
  brute.nodes[0].hi = glm::vec4(1e30f, 1e30f, 1e30f, std::bit_cast<float>(3000u));
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::vec3 o = glm::vec3(rng.uniform(), rng.uniform(), rng.uniform()) * 14.0f - 2.0f;
    const glm::vec3 d = sampleUniformSphere(rng.uniform2());
    const float a = traceTriangleBvh(bvh, o, d, 0, 1e30f),
                b = traceTriangleBvh(brute, o, d, 0, 1e30f);
    ASSERT_EQ(a < 0, b < 0) << i;
    if (b >= 0) {
      EXPECT_FLOAT_EQ(a, b);
      hits++;
    }
  }
  EXPECT_GT(hits, 500);
}

}  // namespace
}  // namespace nestlight::gi
