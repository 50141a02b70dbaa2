// The command line as a user meets it: exit codes, messages that name the file and position,
// --help, info --json, and the hard input cases end to end.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "test_support.h"

using nestlight::test::readFile;
using nestlight::test::runCli;
using nestlight::test::TempDir;
using nestlight::test::writeFile;
namespace fs = std::filesystem;

namespace {
nlohmann::json infoJson(const std::string& dir) {
  std::string out;
  EXPECT_EQ(runCli("info --json " + dir, &out), 0) << out;
  return nlohmann::json::parse(out);
}
}  // namespace

TEST(Cli, HelpForEverySubcommand) {
  for (const char* c :
       {"", "convert", "info", "verify", "export", "generate", "demo", "bench convert"}) {
    std::string out;
    EXPECT_EQ(runCli(std::string(c) + " --help", &out), 0) << c;
    EXPECT_NE(out.find("Usage"), std::string::npos) << c << ": " << out;
  }
}

TEST(Cli, ConvertInfoVerifyExport) {
  TempDir t;
  std::string out;
  ASSERT_EQ(runCli("generate -n 20000 -o " + t.file("s.las"), &out), 0) << out;
  ASSERT_EQ(runCli("convert " + t.file("s.las") + " -o " + t.file("o") + " --progress json", &out),
            0)
      << out;
  EXPECT_NE(out.find("\"phase\""), std::string::npos);  // JSON progress lines
  nlohmann::json j = infoJson(t.file("o"));
  EXPECT_EQ(j["points"], 20000);
  EXPECT_EQ(j["accounting"]["input"], 20000);
  EXPECT_EQ(j["accounting"]["kept"], 20000);
  EXPECT_EQ(j["accounting"]["duplicates_merged"], 0);
  EXPECT_TRUE(j["accounting"]["rejected"].is_object());
  EXPECT_EQ(j["version"], 2);
  // The text form names the measured spacing of the root level (20,000 points: one node).
  ASSERT_EQ(runCli("info " + t.file("o"), &out), 0) << out;
  EXPECT_NE(out.find("spacing    measured (median per level): L0 "), std::string::npos) << out;
  EXPECT_EQ(runCli("verify " + t.file("o"), &out), 0) << out;
  EXPECT_EQ(runCli("export " + t.file("o") + " -o " + t.file("back.las"), &out), 0) << out;
  EXPECT_NE(out.find("20000 points"), std::string::npos) << out;
  EXPECT_EQ(runCli("export " + t.file("o") + " --level 0 -o " + t.file("root.ply"), &out), 0)
      << out;
}

TEST(Cli, EmptyFileIsAnErrorNamingIt) {
  TempDir t;
  writeFile(t.file("empty.las"), "");
  std::string out;
  EXPECT_NE(runCli("convert " + t.file("empty.las") + " -o " + t.file("o"), &out), 0);
  EXPECT_NE(out.find("empty.las"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(t.file("o") + "/metadata.json"));
  writeFile(t.file("empty.xyz"), "");
  EXPECT_NE(runCli("convert " + t.file("empty.xyz") + " -o " + t.file("o2"), &out), 0);
  EXPECT_NE(out.find("empty.xyz"), std::string::npos) << out;
  // A well-formed file that holds no points converts to an empty octree.
  writeFile(t.file("none.ply"),
            "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty "
            "float z\n"
            "end_header\n");
  ASSERT_EQ(runCli("convert " + t.file("none.ply") + " -o " + t.file("o3"), &out), 0) << out;
  EXPECT_EQ(infoJson(t.file("o3"))["points"], 0);
  EXPECT_EQ(runCli("verify " + t.file("o3"), &out), 0) << out;
}

namespace {
// t/cut.las: a generated 1000-point LAS file with its last 100 bytes cut off.
void writeTruncatedLas(const TempDir& t) {
  std::string out;
  ASSERT_EQ(runCli("generate -n 1000 -o " + t.file("s.las"), &out), 0) << out;
  const std::string bytes = readFile(t.file("s.las"));
  writeFile(t.file("cut.las"), bytes.substr(0, bytes.size() - 100));
}
}  // namespace

TEST(Cli, TruncatedLasFailsUnlessLenient) {
  TempDir t;
  std::string out;
  writeTruncatedLas(t);
  EXPECT_NE(runCli("convert " + t.file("cut.las") + " -o " + t.file("o"), &out), 0);
  EXPECT_NE(out.find("cut.las"), std::string::npos) << out;
  EXPECT_NE(out.find("byte"), std::string::npos) << out;  // the position
  ASSERT_EQ(runCli("convert --lenient " + t.file("cut.las") + " -o " + t.file("o"), &out), 0)
      << out;
  nlohmann::json j = infoJson(t.file("o"));
  EXPECT_LT(j["points"].get<int>(), 1000);
  EXPECT_GT(j["points"].get<int>(), 990);
  EXPECT_FALSE(j["sources"][0]["warnings"].empty());
}

TEST(Cli, HeaderClaimingFewerPointsWarns) {
  TempDir t;
  std::string out;
  // An ascii PLY that declares 2 vertices but holds 3 lines of data.
  writeFile(t.file("p.ply"),
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty "
            "float z\n"
            "end_header\n1 2 3\n4 5 6\n7 8 9\n");
  // The declared vertices are read; the rest is reported, not silently dropped or invented.
  ASSERT_EQ(runCli("convert " + t.file("p.ply") + " -o " + t.file("o"), &out), 0) << out;
  nlohmann::json j = infoJson(t.file("o"));
  EXPECT_EQ(j["points"], 2);
  ASSERT_FALSE(j["sources"][0]["warnings"].empty()) << j.dump();
  EXPECT_NE(out.find("warning"), std::string::npos) << out;
}

TEST(Cli, BigEndianPlyWithUnknownPropertiesKeepsThem) {
  TempDir t;
  std::string body;
  auto be32 = [&](const void* v) {
    const char* c = static_cast<const char*>(v);
    body += {c[3], c[2], c[1], c[0]};
  };
  for (int i = 0; i < 3; ++i) {
    float x = 1.5f * i, y = 2.0f, z = -1.0f * i;
    int32_t quality = 1000 + i;
    be32(&x), be32(&y), be32(&z), be32(&quality);
  }
  writeFile(
      t.file("be.ply"),
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty int quality\nend_header\n" +
          body);
  std::string out;
  ASSERT_EQ(runCli("convert " + t.file("be.ply") + " -o " + t.file("o"), &out), 0) << out;
  nlohmann::json j = infoJson(t.file("o"));
  EXPECT_EQ(j["points"], 3);
  bool found = false;
  for (auto& a : j["attributes"]) found = found || (a["name"] == "quality" && a["type"] == "int32");
  EXPECT_TRUE(found) << j["attributes"].dump();
  ASSERT_EQ(runCli("export " + t.file("o") + " -o " + t.file("back.ply"), &out), 0) << out;
  std::string back = readFile(t.file("back.ply"));
  EXPECT_NE(back.find("property int quality"), std::string::npos);
}

TEST(Cli, TruncatedLazNamesFileAndPosition) {
  TempDir t;
  writeFile(t.file("x.laz"), "LASF");
  std::string out;
  EXPECT_NE(runCli("convert " + t.file("x.laz") + " -o " + t.file("o"), &out), 0);
  EXPECT_NE(out.find(t.file("x.laz") + ": byte 4: file ends inside the LAS header"),
            std::string::npos)
      << out;
}

TEST(Cli, MemoryFarBelowInputSize) {
  TempDir t;
  std::string out;
  ASSERT_EQ(runCli("generate -n 1500000 -o " + t.file("s.las"), &out), 0) << out;
  ASSERT_EQ(
      runCli("convert " + t.file("s.las") + " -o " + t.file("o") + " --memory 16M --progress quiet",
             &out),
      0)
      << out;
  nlohmann::json j = infoJson(t.file("o"));
  EXPECT_EQ(j["points"], 1500000);
  EXPECT_GT(j["build"]["chunks"].get<int>(), 4);
  EXPECT_EQ(runCli("verify " + t.file("o"), &out), 0) << out;
}

TEST(Cli, VerifyFailsOnDamageWithNonZeroExit) {
  TempDir t;
  std::string out;
  ASSERT_EQ(runCli("generate -n 5000 -o " + t.file("s.las"), &out), 0);
  ASSERT_EQ(runCli("convert " + t.file("s.las") + " -o " + t.file("o") + " --progress quiet", &out),
            0);
  fs::resize_file(t.file("o") + "/octree.bin", fs::file_size(t.file("o") + "/octree.bin") - 10);
  // A failed check exits 2, a missing input (a user error) 1.
  EXPECT_EQ(runCli("verify " + t.file("o"), &out), 2);
  EXPECT_NE(out.find("FAIL"), std::string::npos) << out;
  EXPECT_EQ(runCli("verify " + t.file("nothing-here"), &out), 1);
  EXPECT_NE(out.find("nothing-here: no such file or directory"), std::string::npos) << out;
}

TEST(Cli, DirectoryInputAndUnknownFormat) {
  TempDir t;
  fs::create_directory(t.file("in"));
  std::string out;
  ASSERT_EQ(runCli("generate -n 1000 --seed 1 -o " + t.file("in/a.las"), &out), 0);
  ASSERT_EQ(runCli("generate -n 2000 --seed 2 -o " + t.file("in/b.ply"), &out), 0);
  ASSERT_EQ(runCli("convert " + t.file("in") + " -o " + t.file("o") + " --progress quiet", &out), 0)
      << out;
  EXPECT_EQ(infoJson(t.file("o"))["points"], 3000);
  writeFile(t.file("x.e57"), "?");
  EXPECT_NE(runCli("convert " + t.file("x.e57") + " -o " + t.file("o2"), &out), 0);
  EXPECT_NE(out.find("x.e57"), std::string::npos) << out;
}

// A warning names its file once: the source's warnings are printed after its path, so a
// reader's own "<file>: " in front of one is dropped when it is recorded.
TEST(Cli, WarningsNameTheFileOnce) {
  TempDir t;
  std::string out;
  writeTruncatedLas(t);
  ASSERT_EQ(
      runCli("convert --lenient " + t.file("cut.las") + " -o " + t.file("o") + " --progress quiet",
             &out),
      0)
      << out;
  const size_t line = out.find("warning");
  ASSERT_NE(line, std::string::npos) << out;
  const std::string warning = out.substr(line, out.find('\n', line) - line);
  const std::string name = t.file("cut.las");
  ASSERT_NE(warning.find(name), std::string::npos) << warning;
  EXPECT_EQ(warning.find(name, warning.find(name) + name.size()), std::string::npos) << warning;
  const std::string recorded = infoJson(t.file("o"))["sources"][0]["warnings"][0];
  EXPECT_EQ(recorded.find(name), std::string::npos) << recorded;
}

// Exports make a missing output folder, as convert and the Potree export do (they used to fail
// naming a .tmp file).
TEST(Cli, ExportMakesAMissingOutputFolder) {
  TempDir t;
  std::string out;
  ASSERT_EQ(runCli("generate -n 2000 -o " + t.file("s.las"), &out), 0) << out;
  ASSERT_EQ(runCli("convert " + t.file("s.las") + " -o " + t.file("o") + " --progress quiet", &out),
            0)
      << out;
  for (const char* f : {"new/a/all.las", "new/b/all.laz", "new/c/all.ply"}) {
    ASSERT_EQ(runCli("export " + t.file("o") + " -o " + t.file(f), &out), 0) << f << ": " << out;
    EXPECT_TRUE(fs::exists(t.file(f))) << f;
  }
}

// LAZ output needs the disk space of the .laz file alone: points are compressed as they arrive,
// nothing uncompressed is written first. A file size limit (ulimit -f, in KiB) stands in for a
// nearly full disk: at 1.2 times the .laz file's size the export succeeds (the uncompressed LAS
// written first would once have failed); below the .laz file's size it fails naming the file and
// leaves nothing behind.
TEST(Cli, LazOutputNeedsOnlyTheSpaceOfTheLazFile) {
  TempDir t;
  std::string out;
  const std::string gen = " generate -n 300000 --seed 5 -o ";
  ASSERT_EQ(runCli(gen + t.file("free.laz"), &out), 0) << out;
  ASSERT_EQ(runCli(gen + t.file("free.las"), &out), 0) << out;
  const auto laz = fs::file_size(t.file("free.laz")), las = fs::file_size(t.file("free.las"));
  const uint64_t roomy = laz * 6 / 5;
  ASSERT_GT(las, roomy + roomy / 4) << "the test needs a LAS file well beyond the limit";
  auto limited = [&](uint64_t kib, const std::string& file) {
    const std::string cmd = "bash -c \"trap '' XFSZ; ulimit -f " + std::to_string(kib) + "; exec " +
                            nestlight::test::nestlightBinary() + gen + t.file(file) + "\" 2>&1";
    FILE* f = ::popen(cmd.c_str(), "r");
    out.clear();
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.append(buf, n);
    const int status = ::pclose(f);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  };
  ASSERT_EQ(limited(roomy / 1024, "roomy.laz"), 0) << out;
  EXPECT_EQ(fs::file_size(t.file("roomy.laz")), laz);
  EXPECT_NE(limited(laz / 2 / 1024, "tight.laz"), 0) << out;
  EXPECT_NE(out.find("tight.laz"), std::string::npos) << out;
  EXPECT_NE(out.find("File too large"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(t.file("tight.laz")));
  EXPECT_FALSE(fs::exists(t.file("tight.laz.tmp")));
}

// A scene render takes the streaming options the real-time methods have, refuses those that do
// not apply to scenes, and refuses streaming options for the path tracer, by name; the output's
// folder is made before rendering.
TEST(Cli, SceneRendersApplyOrRefuseScanOptionsByName) {
  nestlight::test::noLeakChecksInGlChildren();  // the renders below run GL
  TempDir t;
  std::string out;
  ASSERT_EQ(
      runCli("make-scene cornell -o " + t.file("room") + " -n 20k --width 24 --height 16 -q", &out),
      0)
      << out;
  const std::string scene = t.file("room/scene.json");
  EXPECT_NE(runCli("render " + scene + " --point-budget 1M --spp 1 -o " + t.file("r.exr"), &out),
            0);
  EXPECT_NE(out.find("--point-budget"), std::string::npos) << out;
  EXPECT_NE(out.find("memory_budget"), std::string::npos) << out;
  EXPECT_NE(
      runCli("render " + scene + " --method raster --camera 0,0,0,1,1,1 -o " + t.file("r.exr"),
             &out),
      0);
  EXPECT_NE(out.find("--camera does not apply to a scene file"), std::string::npos) << out;
  ASSERT_EQ(
      runCli("render " + scene + " --method raster --point-budget 5000 --splatting basic -o " +
                 t.file("made/here/r.exr"),
             &out),
      0)
      << out;
  EXPECT_TRUE(fs::exists(t.file("made/here/r.exr")));
  // The budget reached the method: its image header says so.
  EXPECT_EQ(runCli("render " + scene + " --method raster --point-budget 0 -o " + t.file("r.exr"),
                   &out) == 0,
            false)
      << out;
  EXPECT_NE(out.find("point_budget"), std::string::npos) << out;
}
