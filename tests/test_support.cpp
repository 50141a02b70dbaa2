#include "test_support.h"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::test {

TempDir::TempDir() {
  std::random_device rd;
  auto base = std::filesystem::temp_directory_path();
  for (;;) {
    path_ = base / ("nestlight-test-" + std::to_string(::getpid()) + "-" + std::to_string(rd()));
    if (std::filesystem::create_directory(path_)) break;
  }
}
TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

namespace {

// A build-time path, or the environment's NAME where set: the GPU bundle's test binaries run on
// another machine, from another folder (scripts/gpu-run.sh sets these).
std::string configured(const char* name, const char* builtIn) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : std::string(builtIn);
}

}  // namespace

std::filesystem::path sharedData() {
  std::filesystem::path p = configured("NESTLIGHT_TEST_SHARED_DATA", NESTLIGHT_SHARED_DATA);
  return std::filesystem::exists(p) ? p : std::filesystem::path();
}

std::string nestlightBinary() {
  return configured("NESTLIGHT_TEST_BINARY", NESTLIGHT_BINARY);
}

std::filesystem::path sourceDir() {
  return configured("NESTLIGHT_TEST_SOURCE_DIR", NESTLIGHT_SOURCE_DIR);
}

int runCli(const std::string& args, std::string* output) {
  std::string cmd = nestlightBinary() + " " + args + " 2>&1";
  FILE* f = ::popen(cmd.c_str(), "r");
  if (!f) return -1;
  std::string out;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), f)) > 0) out.append(buf.data(), n);
  int status = ::pclose(f);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

void noLeakChecksInGlChildren() {
  ::setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
}

void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream o(path, std::ios::binary);
  o.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string readFile(const std::string& path) {
  std::ifstream i(path, std::ios::binary);
  std::stringstream ss;
  ss << i.rdbuf();
  return ss.str();
}

Points readAll(PointReader& r, size_t batchSize) {
  Points p;
  PointBatch b;
  while (r.read(b, batchSize)) {
    EXPECT_GT(b.size(), 0u);
    EXPECT_EQ(b.attrs.size(), b.size() * r.header().layout.stride());
    p.xyz.insert(p.xyz.end(), b.xyz.begin(), b.xyz.end());
    p.attrs.insert(p.attrs.end(), b.attrs.begin(), b.attrs.end());
  }
  return p;
}

bool anyContains(const std::vector<std::string>& v, const std::string& s) {
  for (auto& x : v)
    if (x.find(s) != std::string::npos) return true;
  return false;
}

void buildOctreeFrom(const std::filesystem::path& input, const std::filesystem::path& output,
                     uint32_t maxNodePoints) {
  BuildOptions b;
  if (maxNodePoints) b.maxNodePoints = maxNodePoints;
  b.output = output;
  b.progress = ProgressMode::Quiet;
  std::filesystem::remove_all(output);
  std::vector<std::unique_ptr<PointReader>> src;
  src.push_back(openReader(input.string()));
  buildOctree(std::move(src), b);
}

std::string generatedOctree(const TempDir& dir, const std::string& points, double size,
                            const std::string& origin) {
  std::string out;
  EXPECT_EQ(runCli("generate -n " + points + " --size " + std::to_string(size) + " --origin " +
                       origin + " -o " + dir.file("scan.las"),
                   &out),
            0)
      << out;
  EXPECT_EQ(runCli("convert " + dir.file("scan.las") + " -o " + dir.file("scan.octree") +
                       " --progress quiet",
                   &out),
            0)
      << out;
  return dir.file("scan.octree");
}

void writeColourLayer(const std::filesystem::path& dir, const std::string& name,
                      const std::function<std::array<float, 3>(const NodeKey&, size_t)>& colour,
                      double scale) {
  OctreeReader r(dir);
  ColourLayerWriter w(dir, name, scale);
  for (const auto& [key, e] : r.allNodes()) {
    std::vector<float> rgb(size_t(e.numPoints) * 3);
    for (size_t i = 0; i < e.numPoints; ++i) {
      const auto c = colour(key, i);
      rgb[3 * i] = c[0], rgb[3 * i + 1] = c[1], rgb[3 * i + 2] = c[2];
    }
    w.writeNode(key, rgb.data(), e.numPoints);
  }
  w.finish({{"test", true}});
}

void writeLasWithBoundsInset(const SyntheticSpec& spec, const std::string& path, double inset) {
  auto r = openSynthetic(spec);
  {
    auto w = createLasWriter(path, r->header());
    PointBatch b;
    while (r->read(b, 10000)) w->write(b);
    w->close();
  }
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  double v[6];  // max x, min x, max y, min y, max z, min z (LAS 1.2 header bytes 179..226)
  f.seekg(179);
  f.read(reinterpret_cast<char*>(v), sizeof v);
  for (int a = 0; a < 3; ++a) {
    v[2 * a] -= inset;
    v[2 * a + 1] += inset;
  }
  f.seekp(179);
  f.write(reinterpret_cast<const char*>(v), sizeof v);
}

void expectSameNodes(const std::filesystem::path& a, const std::filesystem::path& b) {
  OctreeReader ra(a), rb(b);
  const Metadata& ma = ra.metadata();
  const Metadata& mb = rb.metadata();
  EXPECT_EQ(ma.points, mb.points);
  EXPECT_EQ(ma.nodes, mb.nodes);
  EXPECT_EQ(ma.depth, mb.depth);
  EXPECT_EQ(ma.payloadBytes, mb.payloadBytes);
  EXPECT_EQ(ma.accounting.input, mb.accounting.input);
  EXPECT_EQ(ma.accounting.kept, mb.accounting.kept);
  EXPECT_EQ(ma.accounting.duplicatesMerged, mb.accounting.duplicatesMerged);
  EXPECT_EQ(ma.accounting.rejected, mb.accounting.rejected);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(ma.offset[k], mb.offset[k]);
    EXPECT_EQ(ma.scale[k], mb.scale[k]);
    EXPECT_EQ(ma.bounds.min[k], mb.bounds.min[k]);
    EXPECT_EQ(ma.bounds.max[k], mb.bounds.max[k]);
  }
  EXPECT_EQ(ma.cubeSize, mb.cubeSize);
  auto na = ra.allNodes(), nb = rb.allNodes();
  ASSERT_EQ(na.size(), nb.size());
  auto byKey = [](const auto& x, const auto& y) { return x.first < y.first; };
  std::sort(na.begin(), na.end(), byKey);
  std::sort(nb.begin(), nb.end(), byKey);
  size_t differing = 0;
  for (size_t i = 0; i < na.size(); ++i) {
    ASSERT_EQ(na[i].first, nb[i].first) << "node " << i;
    const bool same = na[i].second.numPoints == nb[i].second.numPoints &&
                      na[i].second.checksum == nb[i].second.checksum &&
                      na[i].second.spacingCode == nb[i].second.spacingCode;
    if (!same && differing++ < 5) ADD_FAILURE() << "node " << na[i].first.name() << " differs";
  }
  EXPECT_EQ(differing, 0u) << "nodes whose points differ";
}

}  // namespace nestlight::test
