// The options that choose a scene's GI method and set it, shared by `render` and `view` so that a
// scene is rendered and viewed with the same words (cli.h: addSceneMethodOptions).
#include <algorithm>
#include <map>

#include "cli.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/render_scene.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace {

// The flags the methods declare (gi::ParameterSpec::flag, e.g. pbgi's --variant, ibl's
// --estimator): --<name> sets gi.parameters.<name>; methods declaring one name share its flag.
void addParameterFlags(CLI::App* cmd, std::map<std::string, std::string>& values,
                       const std::string& group) {
  std::vector<std::pair<const gi::ParameterSpec*, std::string>> flags;  // with their methods
  for (const auto& m : gi::registeredMethods())
    for (const auto& p : m.parameters) {
      if (!p.flag) continue;
      auto same = std::find_if(flags.begin(), flags.end(),
                               [&](const auto& f) { return f.first->name == p.name; });
      if (same == flags.end())
        flags.push_back({&p, "method " + m.name});
      else
        same->second = "methods " + same->second.substr(7) + ", " + m.name;
    }
  for (const auto& [spec, methods] : flags) {
    std::string dashed = spec->name;
    std::replace(dashed.begin(), dashed.end(), '_', '-');
    auto* o = cmd->add_option(
        "--" + dashed, values[spec->name],
        "Scenes, " + methods + ": " + spec->help + " (gi.parameters." + spec->name + ")");
    if (spec->type == gi::ParameterType::Choice) o->check(CLI::IsMember(spec->choices));
    o->group(group);
  }
}

// --param KEY=VALUE: VALUE is JSON (4, 0.5, true) or, failing that, a string (classic).
void setParameterFromText(const std::string& text, gi::SceneRenderOverrides& sc) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error("--param: expected KEY=VALUE, got '" + text + "'");
  const std::string value = text.substr(eq + 1);
  nlohmann::json j = nlohmann::json::parse(value, nullptr, false);
  if (j.is_discarded()) j = value;
  sc.parameters[text.substr(0, eq)] = j;
}

}  // namespace

void addSceneMethodOptions(CLI::App* cmd, gi::SceneRenderOverrides& sc, SceneMethodText& text,
                           const std::string& group) {
  std::string methodHelp = "Scenes: the GI method (default: the scene's gi.method):";
  std::vector<std::string> names;
  for (const auto& m : gi::registeredMethods()) {
    methodHelp += "\n  " + m.name + ": " + m.summary;
    names.push_back(m.name);
  }
  cmd->add_option("--method", sc.method, methodHelp)->check(CLI::IsMember(names))->group(group);
  cmd->add_option("--mode", text.mode,
                  "Scenes: radiance_cache (scan points emit their colour) or albedo (scan points "
                  "reflect with their colour as albedo)")
      ->check(CLI::IsMember({"radiance_cache", "albedo"}))
      ->group(group);
  addParameterFlags(cmd, text.flags, group);
  cmd->add_option("--param", text.params,
                  "Scenes: KEY=VALUE sets gi.parameters.KEY (VALUE as JSON, else a string); the "
                  "method checks it as it checks the scene file's (docs/SCENE.md lists them)")
      ->group(group);
  cmd->add_option("--spp", sc.spp,
                  "Scenes: samples per pixel at most (render: without it a --time-limit lifts the "
                  "scene's cap)")
      ->check(CLI::Range(1, 1 << 24))
      ->group(group);
}

void addSceneBounceOptions(CLI::App* cmd, gi::SceneRenderOverrides& sc, const std::string& group) {
  cmd->add_option("--bounces", sc.bounces, "Scenes: scattering events per path (1: direct light)")
      ->check(CLI::Range(0, 64))
      ->group(group);
  cmd->add_option("--seed", sc.seed, "Scenes: random seed")->group(group);
}

void applySceneMethodOptions(const SceneMethodText& text, gi::SceneRenderOverrides& sc) {
  if (!text.mode.empty())
    sc.mode = text.mode == "albedo" ? gi::RadianceMode::Albedo : gi::RadianceMode::RadianceCache;
  for (const auto& t : text.params) setParameterFromText(t, sc);
  for (const auto& [name, value] : text.flags)
    if (!value.empty()) sc.parameters[name] = value;
}

}  // namespace nestlight::cli
