// `nestlight gl-info`: what OpenGL this machine gives Nestlight headless (platform, vendor,
// renderer, version, the limits and extensions the renderers depend on) and, with --programs,
// every GLSL program of the catalogue (shaders/programs.json) compiled and linked by this driver,
// with the driver's log for each failure. The first command of a GPU run (docs/GPU.md).
#include <epoxy/gl.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/program_catalogue.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace {

std::string glString(GLenum name) {
  const char* s = reinterpret_cast<const char*>(glGetString(name));
  return s ? s : "";
}

}  // namespace

void addGlInfo(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "gl-info",
      "The OpenGL context Nestlight gets headless (EGL device: a GPU; "
      "EGL surfaceless: Mesa llvmpipe):\n"
      "vendor, renderer, version, limits, the extensions the renderers "
      "use; --programs compiles and links\n"
      "every shader program of the project (shaders/programs.json) and "
      "lists failures with the driver's log.\n"
      "Exit 0 when every supported program links, 2 when one fails. NESTLIGHT_SHADER_DIR=DIR reads "
      "shader\nfiles from DIR where it holds them (an edited copy of "
      "shaders/), the embedded ones otherwise.\n"
      "Example: nestlight gl-info --programs --json gl.json");
  auto programs = std::make_shared<bool>(false);
  auto json = std::make_shared<std::string>();
  cmd->add_flag("--programs", *programs, "Compile and link every shader program of the catalogue");
  cmd->add_option("--json", *json, "Also write the results as JSON to this file");
  auto only = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--only", *only,
                  "With --programs: only these programs of the catalogue (names as "
                  "shaders/programs.json gives them,\ncomma-separated), e.g. vpl.shade")
      ->delimiter(',');
  cmd->callback([=, &exitCode]() {
    for (const std::string& name : *only) {
      bool known = false;
      for (const gl::ProgramSpec& spec : gl::programCatalogue()) known |= spec.name == name;
      if (!known) throw Error("--only", name, "no program of that name in shaders/programs.json");
    }
    auto ctx = gl::createHeadlessContext();
    nlohmann::json out;
    out["context"] = ctx->description();
    out["vendor"] = glString(GL_VENDOR);
    out["renderer"] = glString(GL_RENDERER);
    out["version"] = glString(GL_VERSION);
    out["glsl_version"] = glString(GL_SHADING_LANGUAGE_VERSION);
    out["software"] = ctx->isSoftware();
    auto limit = [&](const char* name, GLenum e) {
      GLint v = 0;
      glGetIntegerv(e, &v);
      out["limits"][name] = v;
    };
    limit("max_texture_size", GL_MAX_TEXTURE_SIZE);
    limit("max_ssbo_bindings", GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
    limit("max_compute_invocations", GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS);
    limit("max_compute_shared_bytes", GL_MAX_COMPUTE_SHARED_MEMORY_SIZE);
    limit("max_array_texture_layers", GL_MAX_ARRAY_TEXTURE_LAYERS);
    GLint64 ssbo = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &ssbo);
    out["limits"]["max_ssbo_block_bytes"] = ssbo;
    for (const char* ext :
         {"GL_NV_shader_atomic_int64", "GL_ARB_gpu_shader_int64", "GL_ARB_shader_ballot",
          "GL_KHR_shader_subgroup", "GL_NV_shader_atomic_float", "GL_ARB_bindless_texture"})
      out["extensions"][ext] = epoxy_has_gl_extension(ext);
    std::printf("context   %s\nvendor    %s\nrenderer  %s\nversion   %s\nGLSL      %s\n",
                ctx->description().c_str(), out["vendor"].get<std::string>().c_str(),
                out["renderer"].get<std::string>().c_str(),
                out["version"].get<std::string>().c_str(),
                out["glsl_version"].get<std::string>().c_str());
    for (const auto& [k, v] : out["limits"].items())
      std::printf("%-26s %lld\n", k.c_str(), v.get<long long>());
    for (const auto& [k, v] : out["extensions"].items())
      std::printf("%-26s %s\n", k.c_str(), v.get<bool>() ? "yes" : "no");
    int failed = 0;
    if (*programs) {
      const std::vector<gl::ProgramCheck> checks = gl::checkCatalogue(*only);
      int ok = 0, unsupported = 0;
      double ms = 0;
      std::printf("\n%-28s %-22s %-12s %9s\n", "program", "defines", "status", "ms");
      for (const auto& c : checks) {
        std::printf("%-28s %-22s %-12s %9.1f\n", c.name.c_str(), c.defines.c_str(),
                    gl::statusName(c.status), c.ms);
        if (c.status == gl::ProgramCheck::Status::Failed) std::printf("%s\n", c.log.c_str());
        ok += c.status == gl::ProgramCheck::Status::Ok;
        failed += c.status == gl::ProgramCheck::Status::Failed;
        unsupported += c.status == gl::ProgramCheck::Status::Unsupported;
        ms += c.ms;
        out["programs"].push_back({{"name", c.name},
                                   {"defines", c.defines},
                                   {"status", gl::statusName(c.status)},
                                   {"ms", c.ms},
                                   {"log", c.log}});
      }
      out["programs_summary"] = {
          {"ok", ok}, {"failed", failed}, {"unsupported", unsupported}, {"ms", ms}};
      std::printf(
          "\n%d programs linked, %d failed, %d need extensions this driver lacks; %.0f ms\n", ok,
          failed, unsupported, ms);
    }
    if (!json->empty()) {
      std::ofstream f(*json);
      if (!(f << out.dump(1) << "\n")) throw Error(*json, "", "cannot write");
    }
    exitCode = failed ? kExitCheckFailed : kExitOk;
  });
}

}  // namespace nestlight::cli
