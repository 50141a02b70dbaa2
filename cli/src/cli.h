// The `nestlight` command line: one program, sub-commands as in git and PDAL.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/progress.h"
#include "nestlight/frame/view_state.h"

namespace nestlight::viewer {
struct RenderJob;
}
namespace nestlight::gi {
struct SceneRenderOverrides;
}

namespace nestlight::cli {

// Render options shared by `render` and `demo` that need parsing after CLI11 is done.
struct RenderOptionText {
  std::string camera, view = "35,30", rasteriser = "points", splatting = "hqs", colour;
  std::string pointBudget = "5M", gpuBudget = "512M", uploadBudget = "32M";
  CLI::Option* edl = nullptr;  // --colour hdr turns eye-dome lighting off unless --edl is given
  std::string state, clip;     // --state view.json, --clip volumes.json
};
void addRenderOptions(CLI::App* cmd, viewer::RenderJob& job,
                      std::shared_ptr<RenderOptionText> text);
void applyRenderOptions(viewer::RenderJob& job, const RenderOptionText& text);
// --state and --clip, after applyRenderOptions: the view state's camera, colouring, budgets,
// splatting and clipping where the command line (`given`) does not say otherwise, and --clip's
// volumes over the state's. Warns when the state was saved from an octree elsewhere.
void applyViewStateOptions(viewer::RenderJob& job, const RenderOptionText& text,
                           const std::function<bool(const char*)>& given);
// A loaded state's part of applyViewStateOptions (no file read, no warning).
void applyViewState(viewer::RenderJob& job, const frame::ViewState& state,
                    const std::function<bool(const char*)>& given);
// The same for a scene file (`render`/`view` scene.json --state/--clip): the state's camera, GI
// method and parameters (when the method is the one rendered) and clipping volumes go into `sc`,
// --clip's volumes too (added to every scan's); options given win. Its colouring, budgets and
// splatting are the points view's: `view` takes them through applyViewStateOptions. Returns the
// state (none without --state) for its annotations and measurements.
std::optional<frame::ViewState> applyViewStateToScene(const std::string& sceneFile,
                                                      const RenderOptionText& text,
                                                      const std::function<bool(const char*)>& given,
                                                      gi::SceneRenderOverrides& sc);

// The options of scene files that choose and set the GI method, shared by `render` and `view`
// (cli_scene_options.cpp). addSceneMethodOptions: --method, --mode, the flags the methods declare
// (--variant, --estimator), --param KEY=VALUE, --spp; addSceneBounceOptions: --bounces, --seed.
// applySceneMethodOptions, after parsing, sets the mode and the parameters in `sc`.
struct SceneMethodText {
  std::string mode;
  std::map<std::string, std::string> flags;  // parameter name: value ("" when not given)
  std::vector<std::string> params;           // --param KEY=VALUE
};
void addSceneMethodOptions(CLI::App* cmd, gi::SceneRenderOverrides& sc, SceneMethodText& text,
                           const std::string& group);
void addSceneBounceOptions(CLI::App* cmd, gi::SceneRenderOverrides& sc, const std::string& group);
void applySceneMethodOptions(const SceneMethodText& text, gi::SceneRenderOverrides& sc);

// Each adds its sub-command; the callback stores the exit code in `exitCode`.
void addConvert(CLI::App& app, int& exitCode);
void addInfo(CLI::App& app, int& exitCode);
void addVerify(CLI::App& app, int& exitCode);
void addExport(CLI::App& app, int& exitCode);
void addProfile(CLI::App& app, int& exitCode);
void addGenerate(CLI::App& app, int& exitCode);
void addDemo(CLI::App& app, int& exitCode);
void addBench(CLI::App& app, int& exitCode);
void addStress(CLI::App& app, int& exitCode);
void addRender(CLI::App& app, int& exitCode);
void addView(CLI::App& app, int& exitCode);
void addBenchRender(CLI::App& app, int& exitCode);      // after addBench: a sub-command of `bench`
void addBenchGi(CLI::App& app, int& exitCode);          // after addBench: a sub-command of `bench`
void addBenchFrame(CLI::App& app, int& exitCode);       // after addBench: a sub-command of `bench`
void addBenchProjection(CLI::App& app, int& exitCode);  // after addBench
void addBenchStream(CLI::App& app, int& exitCode);      // after addBench: a sub-command of `bench`
void addMakeScene(CLI::App& app, int& exitCode);
void addSurfels(CLI::App& app, int& exitCode);
void addCompare(CLI::App& app, int& exitCode);
void addExpandHdr(CLI::App& app, int& exitCode);
void addBakeRadiance(CLI::App& app, int& exitCode);
void addColourMatch(CLI::App& app, int& exitCode);
void addBenchHdr(CLI::App& app, int& exitCode);         // after addBench: a sub-command of `bench`
void addBenchIbl(CLI::App& app, int& exitCode);         // after addBench: a sub-command of `bench`
void addBenchDiffrender(CLI::App& app, int& exitCode);  // after addBench: a sub-command of `bench`
void addBenchLaz(CLI::App& app, int& exitCode);         // after addBench: a sub-command of `bench`
void addBenchClip(CLI::App& app, int& exitCode);        // after addBench: a sub-command of `bench`
void addGlInfo(CLI::App& app, int& exitCode);

// "5M" = 5,000,000, "800k", "1.5G", "1B" (a billion), plain numbers: point counts are decimal.
uint64_t parseCount(const std::string& text, const std::string& option = "");
// "1G", "512M", "64k", plain bytes.
uint64_t parseBytes(const std::string& text);
// Files as given; a directory stands for its supported point files, sorted by name.
std::vector<std::string> expandInputs(const std::vector<std::string>& inputs);
// "1,4.5,16": comma-separated numbers; Error naming `option` and the item that is not one.
std::vector<double> parseNumberList(const std::string& text, const std::string& option);
// Counts, sizes and the CPU's name for reports, as the benchmarks print them.
using bench::cpuName;
using bench::humanBytes;
using bench::humanCount;
// --progress: "terminal", "json", "quiet" (or "none"); anything else is Auto.
ProgressMode parseProgress(const std::string& s);

// The exit codes (README "Exit codes", `nestlight --help`): 0 done; 1 a user error (an unknown
// command or option, a bad value, an input file that is missing, of the wrong kind or damaged:
// every CLI11 parse error and every nestlight::Error); 2 a check failed (verify, stress,
// gl-info's programs, the demo's verify, an unusable colour-match); 3 the program or the system
// failed (out of memory, a file system error, an internal error).
enum ExitCode : int { kExitOk = 0, kExitUserError = 1, kExitCheckFailed = 2, kExitFailure = 3 };
// Parses and runs the command line (cli_errors.cpp): US spellings of the options and commands
// (--color, --rasterizer, color-match) are read as the UK ones; parse errors name the
// sub-command and suggest the nearest command, option or value; returns the exit code (the one
// the sub-command stored in `exitCode` when it ran).
int runCommandLine(CLI::App& app, int argc, char** argv, const int& exitCode);
// Edit distance (insertions, deletions, substitutions, swaps of neighbours) for suggestions.
size_t editDistance(const std::string& a, const std::string& b);
// The nearest of `candidates` to `word` within a few edits ("" when none is near).
std::string nearestName(const std::string& word, const std::vector<std::string>& candidates);
// `path` as an input that must exist: Error naming it, and a near name in its folder (a typo).
void requireExists(const std::string& path);
// `path` as the octree `command` reads (info, verify, render, view, export): Error when it is
// missing (a near name in its folder), a scan file (with the `nestlight convert` command for it),
// a scene file where none is taken, or a folder of scans or a scene's folder.
void requireOctreeFolder(const std::string& path, const std::string& command);
// "scan.las" or, with spaces and quotes, 'my scan.las': a path as a shell command takes it.
std::string shellQuoted(const std::string& path);

}  // namespace nestlight::cli
