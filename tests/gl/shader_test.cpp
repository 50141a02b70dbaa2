// Shader embedding and preprocessing: #include expansion, #line mapping back to files, and that
// every embedded program compiles on the machine's GL (llvmpipe in CI).
#include <epoxy/gl.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <set>

#include "nestlight/gl/context.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/program_catalogue.h"
#include "nestlight/shaders/embedded.h"
#include "test_support.h"

using namespace nestlight;

TEST(Shaders, EveryFileIsEmbedded) {
  std::vector<std::string> paths;
  for (const auto& f : shaders::embeddedFiles()) paths.emplace_back(f.path);
  for (const char* want : {"common/point_data.glsl", "common/octahedral.glsl", "points/points.vert",
                           "points/raster_depth.comp", "points/edl.frag"})
    EXPECT_NE(std::find(paths.begin(), paths.end(), want), paths.end()) << want;
}

namespace {

// Identifiers of a GLSL text that the language reserves: GLSL 4.50, section 3.6, reserves these
// for future use, and `packed` (reserved up to GLSL 1.20 and in GLSL ES) is still refused by
// NVIDIA's compiler (seen on an H200 with driver 580: "unexpected reserved word packed") though
// Mesa and glslang take it. Comments are skipped; the result is "word at line N".
std::vector<std::string> reservedIdentifiers(const std::string& text) {
  static const std::set<std::string> reserved = {
      "common",  "partition", "active",    "asm",      "class",     "union",         "enum",
      "typedef", "template",  "this",      "resource", "goto",      "inline",        "noinline",
      "public",  "static",    "extern",    "external", "interface", "long",          "short",
      "half",    "fixed",     "unsigned",  "superp",   "input",     "output",        "hvec2",
      "hvec3",   "hvec4",     "fvec2",     "fvec3",    "fvec4",     "sampler3DRect", "filter",
      "sizeof",  "cast",      "namespace", "using",    "packed"};
  std::vector<std::string> found;
  int line = 1;
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (text.compare(i, 2, "//") == 0) {
      i = text.find('\n', i);
      if (i == std::string::npos) break;
    } else if (text.compare(i, 2, "/*") == 0) {
      const size_t end = text.find("*/", i + 2);
      for (size_t k = i; k < std::min(end, text.size()); ++k) line += text[k] == '\n';
      if (end == std::string::npos) break;
      i = end + 2;
    } else if (c == '#') {  // directives (#include "common/...") hold paths, not identifiers
      i = text.find('\n', i);
      if (i == std::string::npos) break;
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      size_t j = i;
      while (j < text.size() &&
             (std::isalnum(static_cast<unsigned char>(text[j])) || text[j] == '_'))
        ++j;
      const std::string word = text.substr(i, j - i);
      if (reserved.count(word)) found.push_back(word + " at line " + std::to_string(line));
      i = j;
    } else {
      ++i;
    }
  }
  return found;
}

}  // namespace

TEST(Shaders, NoFileUsesAReservedWordAsAnIdentifier) {
  // The scanner finds them where they are and nowhere else.
  EXPECT_EQ(reservedIdentifiers("uint64_t packed[];\n// packed in a comment\n/* filter\n */ int "
                                "input;\n#include \"common/a.glsl\"\nfloat filtered;"),
            (std::vector<std::string>{"packed at line 1", "input at line 4"}));
  int files = 0;
  for (const auto& f : shaders::embeddedFiles()) {
    const std::string path(f.path);
    if (path.size() < 5 || path.compare(path.size() - 5, 5, ".json") == 0) continue;
    ++files;
    for (const std::string& hit : reservedIdentifiers(std::string(f.text)))
      ADD_FAILURE() << "shaders/" << f.path << ": " << hit;
  }
  EXPECT_GT(files, 50);
}

TEST(Shaders, IncludesExpandOnceWithLineDirectives) {
  gl::PreprocessedSource s =
      gl::preprocessShader("points/raster_depth.comp", {{"TEST_DEFINE", "3"}});
  EXPECT_EQ(s.text.rfind("#version 450 core\n", 0), 0u);
  EXPECT_NE(s.text.find("#define TEST_DEFINE 3\n"), std::string::npos);
  // raster_depth includes raster_common, which includes point_data, which includes the frame
  // interface, octahedral and the colour word's decoders (which include the sRGB curve), then the
  // clipping volumes' test (whose include of the frame interface adds nothing).
  ASSERT_EQ(s.files.size(), 8u);
  EXPECT_EQ(s.files[0], "points/raster_depth.comp");
  EXPECT_EQ(s.files[1], "points/raster_common.glsl");
  EXPECT_EQ(s.files[2], "common/point_data.glsl");
  EXPECT_EQ(s.files[3], "interface/frame_interface.glsl");
  EXPECT_EQ(s.files[4], "common/colour_word.glsl");
  EXPECT_EQ(s.files[5], "common/srgb.glsl");
  EXPECT_EQ(s.files[6], "common/octahedral.glsl");
  EXPECT_EQ(s.files[7], "common/clip_volumes.glsl");
  // The octahedral decoder appears once although two files could pull it in.
  size_t first = s.text.find("vec3 decodeNormal(");
  ASSERT_NE(first, std::string::npos);
  EXPECT_EQ(s.text.find("vec3 decodeNormal(", first + 1), std::string::npos);
  // After the include, numbering resumes in the including file at the next line.
  EXPECT_NE(s.text.find("#line 2 0\n"), std::string::npos);
}

// NESTLIGHT_SHADER_DIR: a folder's copy of a file replaces the embedded one (with its includes
// resolved there or embedded), files it lacks stay embedded; how a driver's refusal is bisected
// on a lent GPU with the same binary.
TEST(Shaders, ShaderDirReplacesTheFilesItHolds) {
  test::TempDir t;
  std::filesystem::create_directories(t.path() / "points");
  {
    std::ofstream f(t.path() / "points/raster_common.glsl");
    f << "// edited\n#include \"../common/point_data.glsl\"\nfloat editedMarker;\n";
  }
  ::setenv("NESTLIGHT_SHADER_DIR", t.path().c_str(), 1);
  gl::PreprocessedSource s = gl::preprocessShader("points/raster_depth.comp");
  ::unsetenv("NESTLIGHT_SHADER_DIR");
  EXPECT_NE(s.text.find("float editedMarker;"), std::string::npos);
  EXPECT_NE(s.text.find("vec3 decodeNormal("), std::string::npos);  // embedded, via the edit
  EXPECT_EQ(s.files[0], "points/raster_depth.comp");
  gl::PreprocessedSource plain = gl::preprocessShader("points/raster_depth.comp");
  EXPECT_EQ(plain.text.find("editedMarker"), std::string::npos);
}

TEST(Shaders, MissingFileIsNamed) {
  Error e = test::errorOf([] { gl::preprocessShader("points/none.frag"); });
  EXPECT_NE(std::string(e.what()).find("points/none.frag"), std::string::npos);
}

TEST(Shaders, LogsMapBackToFiles) {
  const std::vector<std::string> files = {"points/a.frag", "common/b.glsl"};
  EXPECT_EQ(gl::mapShaderLog("1:7(12): error: `x' undeclared\n", files),
            "shaders/common/b.glsl:7:12: error: `x' undeclared\n");
  EXPECT_EQ(gl::mapShaderLog("0(3) : error C1008: undefined variable", files),
            "shaders/points/a.frag:3 : error C1008: undefined variable");
}

TEST(Shaders, CompileErrorNamesFileAndLineOnThisDriver) {
  auto ctx = gl::createHeadlessContext();
  // A real driver log for a broken include: line 2 of the second file.
  gl::PreprocessedSource src;
  src.files = {"points/main.frag", "common/broken.glsl"};
  src.text =
      "#version 450 core\n#line 1 0\nout vec4 c;\n#line 1 1\nfloat f() { return 1.0; }\nfloat g() "
      "{ return undeclared_name; }\n#line 3 0\nvoid main() { c = vec4(f()); }\n";
  GLuint s = glCreateShader(GL_FRAGMENT_SHADER);
  const char* t = src.text.c_str();
  glShaderSource(s, 1, &t, nullptr);
  glCompileShader(s);
  GLint ok = 1;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  EXPECT_FALSE(ok);
  char log[4096] = {};
  glGetShaderInfoLog(s, sizeof log, nullptr, log);
  glDeleteShader(s);
  const std::string mapped = gl::mapShaderLog(log, src.files);
  EXPECT_NE(mapped.find("shaders/common/broken.glsl:2"), std::string::npos) << log;
}

// Headless contexts share EGL's one display per process: ending one (a method destroyed while
// another lives) must leave the others working, and a context made after still works.
TEST(Contexts, OneEndingLeavesTheOthersWorking) {
  auto a = gl::createHeadlessContext();
  auto b = gl::createHeadlessContext();
  b.reset();
  ASSERT_NO_THROW(a->makeCurrent());
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  EXPECT_NE(buffer, 0u);
  glDeleteBuffers(1, &buffer);
  a.reset();
  auto c = gl::createHeadlessContext();
  ASSERT_NO_THROW(c->makeCurrent());
  EXPECT_NE(glGetString(GL_VERSION), nullptr);
}

TEST(Shaders, EveryProgramCompilesAndLinks) {
  auto ctx = gl::createHeadlessContext();
  EXPECT_NE(ctx->description().find("4.5"), std::string::npos) << ctx->description();
  // The whole catalogue, as `nestlight gl-info --programs` checks it on a GPU: nothing fails;
  // only programs needing extensions the driver lacks (64-bit atomics on llvmpipe) are skipped.
  const std::vector<gl::ProgramCheck> checks = gl::checkCatalogue();
  size_t ok = 0;
  for (const auto& c : checks) {
    EXPECT_NE(c.status, gl::ProgramCheck::Status::Failed) << c.name << " " << c.defines << ":\n"
                                                          << c.log;
    if (c.status == gl::ProgramCheck::Status::Unsupported) {
      EXPECT_TRUE(c.name == "points.compute_atomic64" || c.name == "points.compute_resolve64")
          << c.name << ": " << c.log;
    }
    ok += c.status == gl::ProgramCheck::Status::Ok;
  }
  // Each define's values are checked one at a time: more checks than entries.
  EXPECT_GT(checks.size(), gl::programCatalogue().size());
  EXPECT_GE(ok, gl::programCatalogue().size() - 2);
}

// Every stage file is part of some catalogued program, so a new shader cannot escape the driver
// check; and every catalogued stage exists.
TEST(Shaders, CatalogueCoversEveryStageFile) {
  std::set<std::string> listed;
  for (const auto& p : gl::programCatalogue()) {
    EXPECT_FALSE(p.name.empty());
    for (const auto& st : p.stages) listed.insert(st.path);
    EXPECT_EQ(gl::findProgram(p.stages), &p) << p.name << ": two entries with the same stages";
  }
  std::set<std::string> files;
  for (const auto& f : shaders::embeddedFiles()) {
    const std::string path(f.path);
    const std::string ext = path.substr(path.rfind('.'));
    if (ext == ".vert" || ext == ".frag" || ext == ".comp") files.insert(path);
  }
  for (const auto& f : files)
    EXPECT_TRUE(listed.count(f)) << f << " is in no program of shaders/programs.json";
  for (const auto& f : listed)
    EXPECT_TRUE(files.count(f)) << f << " is listed but is no embedded stage file";
  EXPECT_EQ(gl::findProgram({{GL_COMPUTE_SHADER, "points/raster_colour.comp"},
                             {GL_COMPUTE_SHADER, "points/raster_depth.comp"}}),
            nullptr);
}

// A program that is not in the catalogue (or takes a define it does not list) is refused at once.
TEST(ShadersDeathTest, UncataloguedProgramIsRefused) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_DEATH(
      {
        auto ctx = gl::createHeadlessContext();
        gl::ShaderProgram p({{GL_COMPUTE_SHADER, "tests/ibl_samplers.comp"}},
                            {{"NOT_LISTED", "1"}});
      },
      "does not list the define NOT_LISTED");
  EXPECT_DEATH(
      {
        auto ctx = gl::createHeadlessContext();
        gl::ShaderProgram p(
            {{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/edl.frag"}});
      },
      "is not listed in shaders/programs.json");
}

// Every stage file, including the 64-bit atomic rasteriser that only GPUs compile, passes the
// Khronos reference compiler (glslangValidator) after our preprocessing.
TEST(Shaders, EveryStageValidatesWithGlslang) {
  if (std::system("command -v glslangValidator >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "glslangValidator (glslang-tools) is not installed";
  test::TempDir tmp;
  int checked = 0;
  for (const auto& f : shaders::embeddedFiles()) {
    const std::string path(f.path);
    const std::string ext = path.substr(path.rfind('.'));
    if (ext != ".vert" && ext != ".frag" && ext != ".comp") continue;
    const std::string file = tmp.file("stage" + std::to_string(checked++) + ext);
    test::writeFile(file, gl::preprocessShader(path).text);
    const std::string log = tmp.file("log.txt");
    const int rc = std::system(("glslangValidator " + file + " > " + log + " 2>&1").c_str());
    EXPECT_EQ(rc, 0) << path << ":\n" << test::readFile(log);
  }
  EXPECT_GE(checked, 8);
}
