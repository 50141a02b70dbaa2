// Shared helpers for the unit tests: temporary folders, the shared data folder, running the CLI,
// reading every point of a reader, and catching the nestlight::Error a call throws.
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/node_key.h"

namespace nestlight {
struct SyntheticSpec;
}

namespace nestlight::test {

// A fresh folder under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

// ../shared/data beside the checkout (NESTLIGHT_TEST_SHARED_DATA where set); empty when absent.
std::filesystem::path sharedData();
// The built `nestlight` (NESTLIGHT_TEST_BINARY where set) and the source tree
// (NESTLIGHT_TEST_SOURCE_DIR): the GPU bundle's tests run elsewhere than they were built.
std::string nestlightBinary();
std::filesystem::path sourceDir();

// Runs the built `nestlight` with `args`; returns the exit code, stdout+stderr in `output`.
int runCli(const std::string& args, std::string* output = nullptr);
// For tests whose commands run GL methods: llvmpipe's JIT-compiled shader code allocates blocks
// that LeakSanitizer cannot attribute (tests/CMakeLists.txt turns leak checks off for the GL test
// binaries for the same reason), so child processes started after this get the same setting.
// Leaks of the CLI itself stay covered by the commands that run no GL.
void noLeakChecksInGlChildren();

void writeFile(const std::string& path, const std::string& bytes);
std::string readFile(const std::string& path);
// Converts one point file (any reader's format) into an octree at `output`, quietly, replacing
// what is there.
// maxNodePoints: the converter's leaf size (its default when 0); small values make many nodes,
// for streaming tests.
void buildOctreeFrom(const std::filesystem::path& input, const std::filesystem::path& output,
                     uint32_t maxNodePoints = 0);

// `nestlight generate -n POINTS --size SIZE --origin ORIGIN` written into `dir` and converted to
// `dir`/scan.octree by the CLI, as a user would; returns the octree's path.
std::string generatedOctree(const TempDir& dir, const std::string& points, double size,
                            const std::string& origin);

// Writes colour layer `name` into the octree at `dir`: `colour(key, i)` for point i of each node
// (linear RGB), stored divided by `scale` (nestlight/octree/colour_layer.h).
void writeColourLayer(const std::filesystem::path& dir, const std::string& name,
                      const std::function<std::array<float, 3>(const NodeKey&, size_t)>& colour,
                      double scale = 1.0);

// Every point a reader gave, its batches concatenated.
struct Points {
  std::vector<double> xyz;
  std::vector<uint8_t> attrs;
  size_t size() const { return xyz.size() / 3; }
};

// Reads `r` to its end in batches of up to `batchSize`, checking that each batch is non-empty and
// holds the layout's stride of attribute bytes per point.
Points readAll(PointReader& r, size_t batchSize = 1000);

// Component `component` of attribute `name` of point `point` of `p`, read from `r`'s layout;
// fails the test (and gives T()) when the attribute is absent or not of T's size.
template <typename T>
T attrAt(const Points& p, const PointReader& r, size_t point, std::string_view name,
         int component = 0) {
  const PointLayout& l = r.header().layout;
  const int idx = l.find(name);
  EXPECT_GE(idx, 0) << "no attribute " << name;
  if (idx < 0) return T();
  EXPECT_EQ(scalarSize(l[size_t(idx)].type), sizeof(T)) << name;
  T v;
  std::memcpy(&v,
              p.attrs.data() + point * l.stride() + l.offset(size_t(idx)) + component * sizeof(T),
              sizeof(T));
  return v;
}

// Runs `f` and returns the nestlight::Error it throws (failing the test if it throws none).
template <typename F>
Error errorOf(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no nestlight::Error thrown";
  return Error("none");
}

// Whether any string of `v` contains `s`.
bool anyContains(const std::vector<std::string>& v, const std::string& s);

// A LAS file of `spec`'s points whose header bounds are the true ones moved inward by `inset`
// on every side (negative: outward), as files written by other tools have them.
void writeLasWithBoundsInset(const SyntheticSpec& spec, const std::string& path, double inset);

// Two octrees hold the same nodes, each with the same points in the same order (the payloads'
// checksums: encoding is deterministic) and the same measured spacing, and the same accounting.
// Payloads may lie in any order in the files (they are appended as nodes finish).
void expectSameNodes(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace nestlight::test

// Skips the test with a message when a file of ../shared/data is missing.
#define NL_REQUIRE_SHARED(rel)                                                             \
  do {                                                                                     \
    if (!std::filesystem::exists(::nestlight::test::sharedData() / (rel)))                 \
      GTEST_SKIP() << "../shared/data/" << (rel) << " is absent; skipping real-data test"; \
  } while (0)
