// A GI method's parameters (scene.gi.parameters) as the method declares them: name, type, range,
// default and help, once, in the method's own library. The declaration is what checks a scene's
// parameters (the errors name the file and scene.gi.parameters.<key>, as every scene field's do),
// what fills the method's typed parameters, and what the command line's flags and the viewer's
// panel are made from, so a parameter's name, range and default are written in one place.
#pragma once

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/gi/scene.h"

namespace nestlight::gi {

// Pixels: a list of [x, y] image pixels (top row 0), at most `max` of them.
enum class ParameterType { Integer, Number, Boolean, Choice, String, Pixels };

struct ParameterSpec {
  std::string name;
  ParameterType type = ParameterType::Number;
  double min = -INFINITY, max = INFINITY;  // integer and number
  // Null: the method picks the value (the help says how), and no value in range stands for that.
  nlohmann::json defaultValue;
  std::string help;
  // Choice: the values. Integer: words also accepted instead of a number ("auto").
  std::vector<std::string> choices;
  bool powerOfTwo = false;  // integer
  // Also a flag of `nestlight render` (--<name>, dashes for underscores): the parameter a method
  // is most often run with in another setting (pbgi's variant, ibl's estimator).
  bool flag = false;

  static ParameterSpec integer(std::string name, int64_t min, int64_t max, nlohmann::json value,
                               std::string help);
  static ParameterSpec number(std::string name, double min, double max, double value,
                              std::string help);
  static ParameterSpec boolean(std::string name, bool value, std::string help);
  static ParameterSpec choice(std::string name, std::vector<std::string> choices, std::string value,
                              std::string help);
  static ParameterSpec pixels(std::string name, int maxCount, std::string help);
  // An integer that may be one of `words` instead.
  ParameterSpec orOneOf(std::vector<std::string> words) &&;
  ParameterSpec powersOfTwo() &&;
  ParameterSpec asFlag() &&;
};

using ParameterSpecs = std::vector<ParameterSpec>;

// A scene's parameters checked against a declaration, with the defaults filled in.
class ResolvedParameters {
 public:
  explicit ResolvedParameters(nlohmann::json values) : values_(std::move(values)) {}
  // Whether the value is there: given, or a default that is not null.
  bool has(const std::string& name) const;
  const nlohmann::json& value(const std::string& name) const;
  int64_t integer(const std::string& name) const;
  double number(const std::string& name) const;
  bool boolean(const std::string& name) const;
  std::string string(const std::string& name) const;  // choices and strings
  const nlohmann::json& values() const { return values_; }

 private:
  nlohmann::json values_;  // an object: name to value
};

// Checks the members of scene.gi.parameters that `specs` declare, in the order they are
// declared, and returns them with the others' defaults. Members the specs do not declare are
// left to checkParameterNames (a method built on another checks its own members first, then
// the names of both). Throws nestlight::Error naming the scene file and
// scene.gi.parameters.<key>.
ResolvedParameters resolveParameterValues(const Scene& scene, const ParameterSpecs& specs);
// Fails on a member of scene.gi.parameters that no spec names (a typo must not be ignored).
void checkParameterNames(const Scene& scene, const ParameterSpecs& specs);
void checkParameterNames(const Scene& scene, const std::vector<std::string>& names);
// Both: the names first, then the values.
ResolvedParameters resolveParameters(const Scene& scene, const ParameterSpecs& specs);

std::vector<std::string> parameterNames(const ParameterSpecs& specs);
// "integer in [4, 64]", "one of: classic, mip, x", for help texts and panels.
std::string describeParameterType(const ParameterSpec& spec);

}  // namespace nestlight::gi
