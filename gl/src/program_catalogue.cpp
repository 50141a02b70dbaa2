#include "nestlight/gl/program_catalogue.h"

#include <nlohmann/json.hpp>

#include "nestlight/octree/error.h"
#include "nestlight/shaders/embedded.h"

namespace nestlight::gl {

namespace {

GLenum stageType(const std::string& path) {
  const std::string ext = path.substr(path.rfind('.') + 1);
  if (ext == "vert") return GL_VERTEX_SHADER;
  if (ext == "frag") return GL_FRAGMENT_SHADER;
  if (ext == "comp") return GL_COMPUTE_SHADER;
  NL_CHECK_MSG(false,
               "shaders/programs.json: stage " + path + " is not a .vert, .frag or .comp file");
  return 0;
}

std::vector<ProgramSpec> parseCatalogue() {
  const shaders::EmbeddedFile* file = nullptr;
  for (const auto& f : shaders::embeddedFiles())
    if (std::string(f.path) == "programs.json") file = &f;
  NL_CHECK_MSG(file, "shaders/programs.json is not embedded");
  // The file is part of the build, not user input: a malformed one is a programming error.
  const nlohmann::json j = nlohmann::json::parse(std::string(file->text));
  std::vector<ProgramSpec> out;
  for (const auto& p : j.at("programs")) {
    ProgramSpec s;
    s.name = p.at("name").get<std::string>();
    for (const auto& st : p.at("stages"))
      s.stages.push_back({stageType(st.get<std::string>()), st.get<std::string>()});
    if (p.contains("defines"))
      for (const auto& [k, v] : p.at("defines").items()) {
        s.defines[k] = v.get<std::vector<std::string>>();
        NL_CHECK_MSG(!s.defines[k].empty(),
                     "shaders/programs.json: " + s.name + " lists no value of " + k);
      }
    if (p.contains("requires")) s.extensions = p.at("requires").get<std::vector<std::string>>();
    NL_CHECK_MSG(!s.stages.empty(), "shaders/programs.json: " + s.name + " has no stages");
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

const std::vector<ProgramSpec>& programCatalogue() {
  static const std::vector<ProgramSpec> catalogue = parseCatalogue();
  return catalogue;
}

const ProgramSpec* findProgram(const std::vector<ShaderProgram::Stage>& stages) {
  for (const ProgramSpec& s : programCatalogue()) {
    if (s.stages.size() != stages.size()) continue;
    bool same = true;
    for (size_t i = 0; i < stages.size() && same; ++i)
      same = s.stages[i].path == stages[i].path && s.stages[i].type == stages[i].type;
    if (same) return &s;
  }
  return nullptr;
}

std::string describeStages(const std::vector<ShaderProgram::Stage>& stages) {
  std::string names;
  for (const auto& st : stages) names += (names.empty() ? "" : " + ") + st.path;
  return names;
}

const char* statusName(ProgramCheck::Status s) {
  switch (s) {
    case ProgramCheck::Status::Ok:
      return "ok";
    case ProgramCheck::Status::Failed:
      return "failed";
    case ProgramCheck::Status::Unsupported:
      return "unsupported";
  }
  return "?";
}

}  // namespace nestlight::gl
