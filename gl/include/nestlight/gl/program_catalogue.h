// The catalogue of every GLSL program the project links (shaders/programs.json, embedded with
// the shaders), and a driver check that compiles and links each of them.
//
// ShaderProgram refuses stages that the catalogue does not list, so compiling the catalogue on a
// driver (`nestlight gl-info --programs`) covers every program any method or renderer can make:
// the first run on an NVIDIA GPU finds every shader its stricter GLSL front end rejects at once,
// not one per method as they are reached.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/gl/program.h"

namespace nestlight::gl {

struct ProgramSpec {
  std::string name;                                         // "vpl.bounce"
  std::vector<ShaderProgram::Stage> stages;                 // type from the file's extension
  std::map<std::string, std::vector<std::string>> defines;  // name -> values the check compiles
  std::vector<std::string> extensions;  // GL extensions it needs ("requires"); absent: not checked
};

const std::vector<ProgramSpec>& programCatalogue();
// The entry with exactly these stages in this order, or null.
const ProgramSpec* findProgram(const std::vector<ShaderProgram::Stage>& stages);
std::string describeStages(const std::vector<ShaderProgram::Stage>& stages);

struct ProgramCheck {
  enum class Status { Ok, Failed, Unsupported };
  std::string name, defines;  // defines as "NAME=value ..."
  Status status = Status::Ok;
  std::string log;  // the driver's words (warnings on success, the error on failure)
  double ms = 0;    // compile and link, wall clock
};
const char* statusName(ProgramCheck::Status s);

// Compiles and links one program with `defines` on the current context; never throws for a
// driver's refusal (that is the result).
ProgramCheck checkProgram(const ProgramSpec& spec,
                          const std::vector<std::pair<std::string, std::string>>& defines);
// Every catalogue entry (or those named in `only`), once per listed value of each of its defines.
std::vector<ProgramCheck> checkCatalogue(const std::vector<std::string>& only = {});

}  // namespace nestlight::gl
