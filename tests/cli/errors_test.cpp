// The command line's errors as a user meets them: the exit codes (0 done, 1 a user error, 2 a
// failed check, README "Exit codes"), the nearest command, option or value for a misspelt one, US
// spellings, scan files given where an octree is read, and missing inputs with a near name.
#include <gtest/gtest.h>

#include <filesystem>

#include "nestlight/gi/methods.h"
#include "test_support.h"

using nestlight::test::runCli;
using nestlight::test::TempDir;
using nestlight::test::writeFile;
namespace fs = std::filesystem;

namespace {
bool has(const std::string& out, const std::string& s) {
  return out.find(s) != std::string::npos;
}
}  // namespace

TEST(CliErrors, HelpAndVersionExitZeroAndTheHelpNamesTheExitCodes) {
  std::string out;
  EXPECT_EQ(runCli("--help", &out), 0) << out;
  EXPECT_TRUE(has(out, "Exit codes: 0 done; 1 a user error")) << out;
  EXPECT_TRUE(has(out, "2 a check failed")) << out;
  EXPECT_EQ(runCli("--version", &out), 0) << out;
  EXPECT_EQ(runCli("render --help", &out), 0) << out;
  EXPECT_EQ(runCli("bench gi --help", &out), 0) << out;
}

TEST(CliErrors, MisspeltCommandsSuggestTheNearest) {
  std::string out;
  EXPECT_EQ(runCli("conver", &out), 1) << out;
  EXPECT_TRUE(has(out, "'conver' is not a command of nestlight; did you mean `nestlight convert`?"))
      << out;
  EXPECT_FALSE(has(out, "A subcommand is required")) << out;
  EXPECT_EQ(runCli("veiw x.octree", &out), 1) << out;
  EXPECT_TRUE(has(out, "did you mean `nestlight view`?")) << out;
  EXPECT_EQ(runCli("bench gii", &out), 1) << out;
  EXPECT_TRUE(has(out, "did you mean `nestlight bench gi`?")) << out;
  EXPECT_EQ(runCli("frobnicate", &out), 1) << out;
  EXPECT_TRUE(has(out, "the commands: convert, info, verify")) << out;
  EXPECT_EQ(runCli("", &out), 1) << out;
  EXPECT_TRUE(has(out, "a command is required: convert, info")) << out;
  EXPECT_EQ(runCli("bench", &out), 1) << out;
  EXPECT_TRUE(has(out, "nestlight bench: error: a command is required: convert")) << out;
}

TEST(CliErrors, UnknownOptionsSuggestTheNearestAndExitOne) {
  TempDir t;
  std::string out;
  EXPECT_EQ(runCli("render " + t.file("x.octree") + " --colr rgb", &out), 1) << out;
  EXPECT_TRUE(has(out, "nestlight render: error: unknown option --colr, did you mean --colour?"))
      << out;
  EXPECT_EQ(runCli("convert a.las -o o --dedupe", &out), 1) << out;
  EXPECT_TRUE(has(out, "unknown option --dedupe, did you mean --dedup?")) << out;
  // A value outside a choice: exit 1 (CLI11 would exit 105), with the nearest choice.
  writeFile(t.file("s.json"), "{}");
  EXPECT_EQ(runCli("render " + t.file("s.json") + " --method vpll", &out), 1) << out;
  EXPECT_TRUE(has(out, "--method: 'vpll' is not one of reference, direct")) << out;
  EXPECT_TRUE(has(out, "did you mean vpl?")) << out;
  EXPECT_EQ(runCli("convert a.las -o o --codec zstf", &out), 1) << out;
  EXPECT_TRUE(has(out, "did you mean zstd?")) << out;
  // A number out of range, a missing required option: exit 1 too.
  EXPECT_EQ(runCli("render " + t.file("x.octree") + " --width 0", &out), 1) << out;
  EXPECT_EQ(runCli("convert a.las", &out), 1) << out;
  EXPECT_TRUE(has(out, "--output is required")) << out;
}

TEST(CliErrors, UsSpellingsAreReadAsTheUkOnes) {
  TempDir t;
  std::string out;
  // --color is --colour: the error is the missing octree, not the option.
  EXPECT_EQ(runCli("view " + t.file("none.octree") + " --color rgb", &out), 1) << out;
  EXPECT_TRUE(has(out, "none.octree: no such file or directory")) << out;
  EXPECT_FALSE(has(out, "--color")) << out;
  EXPECT_EQ(
      runCli("render " + t.file("none.octree") + " --color=elevation --rasterizer points", &out), 1)
      << out;
  EXPECT_TRUE(has(out, "none.octree: no such file or directory")) << out;
  EXPECT_EQ(runCli("convert " + t.file("none.las") + " -o o --normal-neighbors 8", &out), 1) << out;
  EXPECT_TRUE(has(out, "none.las: no such file or directory")) << out;
  EXPECT_EQ(runCli("color-match --help", &out), 0) << out;
  EXPECT_TRUE(has(out, "colour-match")) << out;
}

// A scan file where an octree is read: say so, and give the convert command with the user's path.
TEST(CliErrors, ScanFilesGivenForAnOctreeNameTheConvertCommand) {
  TempDir t;
  std::string out;
  for (const char* name :
       {"scan.las", "scan.laz", "area.copc.laz", "scan.ply", "scan.pcd", "scan.xyz", "scan.pts"}) {
    writeFile(t.file(name), "not read");
    const std::string octree = name == std::string("area.copc.laz") ? "area.octree" : "scan.octree";
    for (const char* command : {"info", "verify", "render", "view", "export"}) {
      const std::string extra = command == std::string("export") ? " -o " + t.file("x.las") : "";
      EXPECT_EQ(runCli(std::string(command) + " " + t.file(name) + extra, &out), 1)
          << command << " " << name << ": " << out;
      EXPECT_TRUE(has(out, "scan file, not an octree")) << command << " " << name << ": " << out;
      EXPECT_TRUE(has(out, "\n  nestlight convert " + t.file(name) + " -o " + t.file(octree)))
          << command << " " << name << ": " << out;
      EXPECT_FALSE(has(out, "no metadata.json")) << out;
    }
  }
  EXPECT_EQ(runCli("info " + t.file("area.copc.laz"), &out), 1);
  EXPECT_TRUE(has(out, "a COPC scan file")) << out;
  // A folder of scans.
  fs::create_directory(t.file("scans"));
  writeFile(t.file("scans/a.las"), "x");
  EXPECT_EQ(runCli("info " + t.file("scans"), &out), 1) << out;
  EXPECT_TRUE(has(out, "holds scan files, not an octree")) << out;
  EXPECT_TRUE(has(out, "nestlight convert " + t.file("scans") + " -o " + t.file("scans.octree")))
      << out;
}

// A path with a typo: the file does not exist, and the near name in its folder is suggested.
TEST(CliErrors, MissingInputsNameANearFile) {
  TempDir t;
  fs::create_directory(t.file("room"));
  writeFile(t.file("room/scene.json"), "{}");
  std::string out;
  EXPECT_EQ(runCli("render " + t.file("room/scen.json"), &out), 1) << out;
  EXPECT_TRUE(has(out, t.file("room/scen.json") + ": no such file or directory; did you mean " +
                           t.file("room/scene.json") + "?"))
      << out;
  EXPECT_FALSE(has(out, "-o/--output is required")) << out;
  EXPECT_EQ(runCli("view " + t.file("room/scen.json"), &out), 1) << out;
  EXPECT_TRUE(has(out, "did you mean " + t.file("room/scene.json") + "?")) << out;
  // The scene's folder where its file is meant.
  EXPECT_EQ(runCli("render " + t.file("room"), &out), 1) << out;
  EXPECT_TRUE(has(out, "give its scene file, nestlight render " + t.file("room/scene.json")))
      << out;
  // Nothing near: the folder's absence is named.
  EXPECT_EQ(runCli("info " + t.file("nowhere/x.octree"), &out), 1) << out;
  EXPECT_TRUE(has(out, "no such file or directory (nor is there a folder")) << out;
  EXPECT_EQ(runCli("convert " + t.file("room/scene.jsn") + " -o " + t.file("o"), &out), 1) << out;
  EXPECT_TRUE(has(out, "did you mean " + t.file("room/scene.json") + "?")) << out;
}

// Every registered GI method is named in `render --help`, from the registry.
TEST(CliErrors, RenderHelpNamesEveryRegisteredMethod) {
  std::string out;
  ASSERT_EQ(runCli("render --help", &out), 0) << out;
  const std::string description = out.substr(0, out.find("Usage"));
  for (const std::string& name : nestlight::gi::registeredMethodNames())
    EXPECT_TRUE(has(description, "\n  " + name + " ")) << name << ": " << description;
  EXPECT_FALSE(has(out, "speed against size (and, later, error)")) << out;
  ASSERT_EQ(runCli("view --help", &out), 0) << out;
  EXPECT_FALSE(has(out, "tiles")) << out;
  ASSERT_EQ(runCli("bench --help", &out), 0) << out;
  EXPECT_FALSE(has(out, "and, later, error")) << out;
  ASSERT_EQ(runCli("convert --help", &out), 0) << out;
  EXPECT_TRUE(has(out, "LAZ (.laz")) << out;
  EXPECT_TRUE(has(out, "COPC")) << out;
}
