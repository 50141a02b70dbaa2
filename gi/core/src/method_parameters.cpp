#include "nestlight/gi/method_parameters.h"

#include <sstream>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace {

using json = nlohmann::json;

// The shared validator's checks, so that the messages are those of every other scene field.
json checkValue(const JsonField& v, const ParameterSpec& s) {
  switch (s.type) {
    case ParameterType::Integer: {
      if (!s.choices.empty() && v.value().is_string()) return v.choice(s.choices);
      const int64_t lo = int64_t(s.min), hi = int64_t(s.max);
      const int64_t n = v.integer(lo, hi);
      if (s.powerOfTwo && (n & (n - 1)))
        v.fail("must be a power of two (" + std::to_string(lo) + " to " + std::to_string(hi) + ")");
      return n;
    }
    case ParameterType::Number:
      return v.number(s.min, s.max);
    case ParameterType::Boolean:
      return v.boolean();
    case ParameterType::Choice:
      return v.choice(s.choices);
    case ParameterType::String:
      return v.string();
    case ParameterType::Pixels: {
      if (!v.value().is_array())
        v.fail("expected a list of [x, y] pixels, e.g. [[10, 20], [5, 7]]");
      if (v.arraySize() > size_t(s.max))
        v.fail("at most " + std::to_string(int64_t(s.max)) + " pixels, got " +
               std::to_string(v.arraySize()));
      json out = json::array();
      for (size_t i = 0; i < v.arraySize(); ++i) {
        const JsonField p = v.at(i);
        if (!p.value().is_array() || p.arraySize() != 2) p.fail("expected [x, y]");
        out.push_back({p.at(0).integer(0, 65535), p.at(1).integer(0, 65535)});
      }
      return out;
    }
  }
  return nullptr;
}

JsonField parametersField(const Scene& scene) {
  return JsonField(scene.gi.parameters, "scene.gi.parameters", scene.file.string());
}

}  // namespace

ParameterSpec ParameterSpec::integer(std::string name, int64_t min, int64_t max,
                                     nlohmann::json value, std::string help) {
  ParameterSpec s;
  s.name = std::move(name);
  s.type = ParameterType::Integer;
  s.min = double(min), s.max = double(max);
  s.defaultValue = std::move(value);
  s.help = std::move(help);
  return s;
}

ParameterSpec ParameterSpec::number(std::string name, double min, double max, double value,
                                    std::string help) {
  ParameterSpec s;
  s.name = std::move(name);
  s.type = ParameterType::Number;
  s.min = min, s.max = max;
  s.defaultValue = value;
  s.help = std::move(help);
  return s;
}

ParameterSpec ParameterSpec::boolean(std::string name, bool value, std::string help) {
  ParameterSpec s;
  s.name = std::move(name);
  s.type = ParameterType::Boolean;
  s.defaultValue = value;
  s.help = std::move(help);
  return s;
}

ParameterSpec ParameterSpec::choice(std::string name, std::vector<std::string> choices,
                                    std::string value, std::string help) {
  ParameterSpec s;
  s.name = std::move(name);
  s.type = ParameterType::Choice;
  s.choices = std::move(choices);
  s.defaultValue = std::move(value);
  s.help = std::move(help);
  return s;
}

ParameterSpec ParameterSpec::pixels(std::string name, int maxCount, std::string help) {
  ParameterSpec s;
  s.name = std::move(name);
  s.type = ParameterType::Pixels;
  s.min = 0, s.max = maxCount;
  s.defaultValue = json::array();
  s.help = std::move(help);
  return s;
}

ParameterSpec ParameterSpec::orOneOf(std::vector<std::string> words) && {
  choices = std::move(words);
  return std::move(*this);
}

ParameterSpec ParameterSpec::powersOfTwo() && {
  powerOfTwo = true;
  return std::move(*this);
}

ParameterSpec ParameterSpec::asFlag() && {
  flag = true;
  return std::move(*this);
}

bool ResolvedParameters::has(const std::string& name) const {
  return values_.contains(name) && !values_.at(name).is_null();
}

const json& ResolvedParameters::value(const std::string& name) const {
  NL_CHECK_MSG(values_.contains(name), "undeclared parameter " + name);
  return values_.at(name);
}

int64_t ResolvedParameters::integer(const std::string& name) const {
  return value(name).get<int64_t>();
}

double ResolvedParameters::number(const std::string& name) const {
  return value(name).get<double>();
}

bool ResolvedParameters::boolean(const std::string& name) const {
  return value(name).get<bool>();
}

std::string ResolvedParameters::string(const std::string& name) const {
  return value(name).get<std::string>();
}

ResolvedParameters resolveParameterValues(const Scene& scene, const ParameterSpecs& specs) {
  json out = json::object();
  const JsonField f = parametersField(scene);
  for (const auto& s : specs)
    out[s.name] = f.has(s.name) ? checkValue(f.at(s.name), s) : s.defaultValue;
  return ResolvedParameters(std::move(out));
}

void checkParameterNames(const Scene& scene, const ParameterSpecs& specs) {
  checkParameterNames(scene, parameterNames(specs));
}

void checkParameterNames(const Scene& scene, const std::vector<std::string>& names) {
  if (scene.gi.parameters.is_null()) return;
  parametersField(scene).expectObject(names);
}

ResolvedParameters resolveParameters(const Scene& scene, const ParameterSpecs& specs) {
  checkParameterNames(scene, specs);
  return resolveParameterValues(scene, specs);
}

std::vector<std::string> parameterNames(const ParameterSpecs& specs) {
  std::vector<std::string> names;
  for (const auto& s : specs) names.push_back(s.name);
  return names;
}

std::string describeParameterType(const ParameterSpec& s) {
  std::ostringstream o;
  auto words = [&](const char* before) {
    for (size_t i = 0; i < s.choices.size(); ++i) o << (i ? ", " : before) << s.choices[i];
  };
  switch (s.type) {
    case ParameterType::Integer:
      o << (s.powerOfTwo ? "power of two" : "integer") << " in [" << int64_t(s.min) << ", "
        << int64_t(s.max) << "]";
      words(" or ");
      break;
    case ParameterType::Number:
      o << "number in [" << s.min << ", " << s.max << "]";
      break;
    case ParameterType::Boolean:
      o << "true or false";
      break;
    case ParameterType::Choice:
      words("one of: ");
      break;
    case ParameterType::String:
      o << "string";
      break;
    case ParameterType::Pixels:
      o << "list of [x, y] pixels (at most " << int64_t(s.max) << ")";
      break;
  }
  return o.str();
}

}  // namespace nestlight::gi
