// Colour layers (the HDR colour beside the scan's): round trips at half precision with values
// beyond half range, atomic replacement, a killed write leaving the octree valid and the layer
// absent or whole, verify catching damage, export carrying the layer, and the decoders on
// hostile bytes.
#include "nestlight/octree/colour_layer.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <fstream>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

namespace nestlight {
namespace {

namespace fs = std::filesystem;

fs::path smallOctree(const test::TempDir& tmp) {
  SyntheticSpec spec;
  spec.points = 30000;
  spec.seed = 5;
  BuildOptions o;
  o.output = tmp.path() / "scan.octree";
  o.maxNodePoints = 2000;  // many nodes
  o.progress = ProgressMode::Quiet;
  std::vector<std::unique_ptr<PointReader>> src;
  src.push_back(openSynthetic(spec));
  buildOctree(std::move(src), o);
  return o.output;
}

// A colour that depends on the node and the point, spanning 1e-3 to 1e6 (beyond half range).
std::array<float, 3> colourOf(const NodeKey& k, size_t i) {
  const double e =
      std::fmod(double(k.x * 7 + k.y * 3 + k.z + k.level * 11) + double(i % 97) * 0.09, 9.0) - 3.0;
  const float v = float(std::pow(10.0, e));
  return {v, v * 0.5f, v * 0.25f};
}

void writeLayer(const fs::path& dir, const std::string& name, double scale, float offset = 0) {
  test::writeColourLayer(
      dir, name,
      [&](const NodeKey& key, size_t i) {
        const auto c = colourOf(key, i);
        return std::array<float, 3>{c[0] + offset, c[1] + offset, c[2] + offset};
      },
      scale);
}

TEST(ColourLayer, RoundTripsAtHalfPrecisionBeyondHalfRange) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  // Scale 20 keeps 1e6 below half's 65504; the smallest value, 1e-3 / 20 = 5e-5, falls just
  // below half's smallest normal (6.1e-5) and is stored as a subnormal.
  writeLayer(dir, "hdr", 20.0);
  OctreeReader r(dir);
  const LayerRecord* rec = r.metadata().layer("hdr");
  ASSERT_NE(rec, nullptr);
  EXPECT_EQ(rec->points, r.metadata().points);
  EXPECT_EQ(rec->nodes, r.metadata().nodes);
  EXPECT_EQ(rec->scale, 20.0);
  ColourLayerReader layer(dir, r.metadata(), "hdr");
  double worst = 0;
  for (const auto& [key, e] : r.allNodes()) {
    const std::vector<float> rgb = layer.readNode(key, e.numPoints);
    ASSERT_EQ(rgb.size(), size_t(e.numPoints) * 3);
    for (size_t i = 0; i < e.numPoints; ++i)
      for (int c = 0; c < 3; ++c) {
        const double want = colourOf(key, i)[c], got = rgb[3 * i + size_t(c)];
        worst = std::max(worst, std::abs(got - want) / want);
      }
  }
  // Half floats keep 11 significant bits (relative rounding error 2^-11 = 4.9e-4); subnormals
  // are spaced 2^-24 = 6e-8, which at 5e-5 is a relative rounding error of 6e-4: 2e-3 bounds both.
  EXPECT_LT(worst, 2e-3);
  EXPECT_TRUE(verifyOctree(dir).ok());
}

TEST(ColourLayer, NegativeNonFiniteAndOversizedValuesAreClampedAndCounted) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  OctreeReader r(dir);
  ColourLayerWriter w(dir, "hdr", 1.0);
  uint64_t bad = 0;
  for (const auto& [key, e] : r.allNodes()) {
    std::vector<float> rgb(size_t(e.numPoints) * 3, 0.5f);
    if (e.numPoints >= 3) {
      rgb[0] = -1.0f, rgb[1] = NAN, rgb[2] = INFINITY, rgb[3] = 1e9f;
      bad += 4;
    }
    w.writeNode(key, rgb.data(), e.numPoints);
  }
  EXPECT_EQ(w.clampedValues(), bad);
  w.finish({});
  OctreeReader r2(dir);
  ColourLayerReader layer(dir, r2.metadata(), "hdr");
  for (const auto& [key, e] : r2.allNodes()) {
    if (e.numPoints < 3) continue;
    const auto rgb = layer.readNode(key, e.numPoints);
    EXPECT_EQ(rgb[0], 0.0f);
    EXPECT_EQ(rgb[1], 0.0f);
    EXPECT_EQ(rgb[2], 0.0f);
    EXPECT_EQ(rgb[3], kHalfMax);
    EXPECT_EQ(rgb[4], 0.5f);
  }
  EXPECT_TRUE(verifyOctree(dir).ok());
}

TEST(ColourLayer, AMissingNodeIsAnErrorAndLeavesTheOctreeAsItWas) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  const std::string before = test::readFile((dir / "metadata.json").string());
  {
    OctreeReader r(dir);
    ColourLayerWriter w(dir, "hdr", 1.0);
    auto nodes = r.allNodes();
    for (size_t n = 1; n < nodes.size(); ++n) {  // the root is left out
      std::vector<float> rgb(size_t(nodes[n].second.numPoints) * 3, 1.0f);
      w.writeNode(nodes[n].first, rgb.data(), nodes[n].second.numPoints);
    }
    const Error e = test::errorOf([&] { w.finish({}); });
    EXPECT_NE(std::string(e.what()).find("node r of the octree has no colours"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(test::readFile((dir / "metadata.json").string()), before);
  EXPECT_TRUE(orphanLayerFiles(dir, OctreeReader(dir).metadata()).empty());
}

TEST(ColourLayer, ANewVersionReplacesTheOldAtomically) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  writeLayer(dir, "hdr", 20.0);
  const std::string first = OctreeReader(dir).metadata().layer("hdr")->file;
  writeLayer(dir, "hdr", 20.0, 100.0f);
  OctreeReader r(dir);
  const std::string second = r.metadata().layer("hdr")->file;
  EXPECT_NE(first, second);
  EXPECT_FALSE(fs::exists(dir / first));  // the old version's file is gone
  EXPECT_EQ(r.metadata().layers.size(), 1u);
  ColourLayerReader layer(dir, r.metadata(), "hdr");
  const auto root = layer.readNode(NodeKey::root(), r.node(NodeKey::root())->numPoints);
  EXPECT_NEAR(root[0], colourOf(NodeKey::root(), 0)[0] + 100.0f, 0.1f);
  EXPECT_TRUE(verifyOctree(dir).ok());
}

TEST(ColourLayer, AWriteKilledMidwayLeavesTheOctreeValidAndTheLayerAbsentOrWhole) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  // Killed while writing nodes (no destructor runs): a temporary file, no layer.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    OctreeReader r(dir);
    auto* w = new ColourLayerWriter(dir, "hdr", 1.0);  // never destroyed: as if killed
    const auto nodes = r.allNodes();
    std::vector<float> rgb(size_t(nodes[0].second.numPoints) * 3, 2.0f);
    w->writeNode(nodes[0].first, rgb.data(), nodes[0].second.numPoints);
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  {
    OctreeReader r(dir);
    EXPECT_EQ(r.metadata().layer("hdr"), nullptr);
    const VerifyReport v = verifyOctree(dir);
    EXPECT_TRUE(v.ok());
    ASSERT_EQ(v.notes.size(), 1u);  // the temporary file is reported, not failed
    EXPECT_NE(v.notes[0].find(".layer.tmp"), std::string::npos);
    EXPECT_EQ(removeOrphanLayerFiles(dir, r.metadata()).size(), 1u);
  }
  // A whole layer, then a second version killed after its file was renamed but before
  // metadata.json named it: the first version is still the layer, whole.
  writeLayer(dir, "hdr", 20.0);
  const std::string file = OctreeReader(dir).metadata().layer("hdr")->file;
  fs::copy_file(dir / file, dir / "hdr.0123456789abcdef.layer");
  OctreeReader r(dir);
  EXPECT_EQ(r.metadata().layer("hdr")->file, file);
  const VerifyReport v = verifyOctree(dir);
  EXPECT_TRUE(v.ok());
  EXPECT_EQ(v.layers, 1u);
  EXPECT_EQ(v.notes.size(), 1u);
}

TEST(ColourLayer, VerifyFindsDamageInTheLayer) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  writeLayer(dir, "hdr", 20.0);
  const std::string file = (dir / OctreeReader(dir).metadata().layer("hdr")->file).string();
  std::string bytes = test::readFile(file);
  // A flipped byte in the first payload: a checksum failure naming the layer and the file.
  std::string damaged = bytes;
  damaged[5] ^= 0x40;
  test::writeFile(file, damaged);
  VerifyReport v = verifyOctree(dir);
  ASSERT_FALSE(v.ok());
  EXPECT_TRUE(test::anyContains(v.failures, "layer 'hdr'")) << v.failures[0];
  EXPECT_TRUE(test::anyContains(v.failures, "checksum mismatch")) << v.failures[0];
  // Truncated: the size disagrees with metadata.json; the reader refuses to open it.
  test::writeFile(file, bytes.substr(0, bytes.size() - 7));
  v = verifyOctree(dir);
  ASSERT_FALSE(v.ok());
  EXPECT_TRUE(test::anyContains(v.failures, "bytes where metadata.json records")) << v.failures[0];
  // Deleted: named by metadata.json, so a failure, not a note.
  fs::remove(file);
  v = verifyOctree(dir);
  EXPECT_FALSE(v.ok());
}

TEST(ColourLayer, ExportCarriesTheLayerAsAFloatAttribute) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  writeLayer(dir, "hdr", 20.0);
  const fs::path ply = tmp.path() / "out.ply";
  const uint64_t n = exportOctree(dir, ply);
  auto reader = openReader(ply.string());
  const int at = reader->header().layout.find("hdr_0");
  ASSERT_GE(at, 0) << "export dropped the layer";
  EXPECT_EQ(reader->header().layout[size_t(at)].type, ScalarType::F32);
  const test::Points pts = test::readAll(*reader);
  ASSERT_EQ(pts.size(), n);
  // Every exported value is one of the layer's values: compare the sums over all points.
  double sumExported = 0, sumLayer = 0;
  for (size_t i = 0; i < pts.size(); ++i)
    sumExported += test::attrAt<float>(pts, *reader, i, "hdr_0");
  OctreeReader r(dir);
  ColourLayerReader layer(dir, r.metadata(), "hdr");
  for (const auto& [key, e] : r.allNodes()) {
    const auto rgb = layer.readNode(key, e.numPoints);
    for (size_t i = 0; i < e.numPoints; ++i) sumLayer += rgb[3 * i];
  }
  EXPECT_NEAR(sumExported, sumLayer, 1e-6 * sumLayer);
}

TEST(ColourLayer, DecodersRejectHostileBytes) {
  std::vector<float> out;
  uint64_t clamped = 0;
  const float rgb[6] = {1, 2, 3, 4, 5, 6};
  std::vector<uint8_t> good = encodeColourPayload(rgb, 2, 1.0, clamped);
  EXPECT_EQ(decodeColourPayload(good.data(), good.size(), 2, 1.0, out), "");
  EXPECT_EQ(out[5], 6.0f);
  EXPECT_NE(decodeColourPayload(good.data(), good.size(), 3, 1.0, out), "");      // lying count
  EXPECT_NE(decodeColourPayload(good.data(), good.size() / 2, 2, 1.0, out), "");  // truncated
  const uint8_t junk[5] = {1, 2, 3, 4, 5};
  EXPECT_NE(decodeColourPayload(junk, 5, 1, 1.0, out), "");
  std::vector<LayerIndexEntry> entries;
  EXPECT_NE(parseLayerIndex(junk, 5, entries), "");  // not whole entries
  std::vector<uint8_t> index(kLayerIndexEntryBytes, 0);
  index[0] = 3;  // level 3, x = 9: outside the level
  index[4] = 9;
  EXPECT_NE(parseLayerIndex(index.data(), index.size(), entries), "");
}

// "rgb" is what scene files call the recorded colour: a layer of that name could never be
// chosen, so it is refused, as are names that are not file names.
TEST(ColourLayer, ReservedAndMalformedNamesAreRefused) {
  test::TempDir tmp;
  const fs::path dir = smallOctree(tmp);
  for (const char* bad : {"rgb", "", "a/b", "a.b"}) {
    const Error e = test::errorOf([&] { ColourLayerWriter w(dir, bad, 1.0); });
    EXPECT_NE(std::string(e.what()).find("layer name"), std::string::npos) << e.what();
  }
  EXPECT_NE(
      std::string(test::errorOf([&] { checkLayerName("rgb"); }).what()).find("recorded colour"),
      std::string::npos);
  EXPECT_NO_THROW(checkLayerName("hdr"));
  EXPECT_TRUE(orphanLayerFiles(dir, OctreeReader(dir).metadata()).empty());
}

}  // namespace
}  // namespace nestlight
