// `nestlight export --format potree`: the Potree 2.0 dataset is read back by a parser written here
// from the format's description (PotreeConverter 2's output as the Potree viewer loads it), sharing
// nothing with the exporter, and compared node by node and point by point with the octree.
#include "nestlight/converters/potree_export.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/octree_writer.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::runCli;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------------------------
// An independent reader of Potree 2.0 datasets. Facts used:
//  - metadata.json: "version" "2.0", "points", "hierarchy" {firstChunkSize, stepSize, depth},
//    "offset" [3], "scale" [3], "spacing", "boundingBox" {min, max}, "encoding" "DEFAULT",
//    "attributes": [{name, description, size, numElements, elementSize, type, min, max}], the
//    first being "position" (int32 x3); a point record is the attributes' bytes in list order.
//  - hierarchy.bin: 22-byte entries (u8 type 0 normal / 1 leaf / 2 proxy, u8 child mask,
//    u32 numPoints, u64 byteOffset, u64 byteSize), little endian. The chunk at 0 of
//    firstChunkSize bytes starts with the root; a chunk lists its root and then, walking a queue,
//    the children (in index order) of every entry that is not a proxy; a proxy's byteOffset and
//    byteSize locate its own chunk, which starts with its real entry.
//  - octree.bin: each node's records at byteOffset, byteSize bytes; world position of a point is
//    int32 * scale + offset per axis. Child i of node "rN" is "rNi", i = (x << 2) | (y << 1) | z.
// ---------------------------------------------------------------------------------------------
struct PAttribute {
  std::string name, type;
  int size = 0, numElements = 0, elementSize = 0;
  size_t offset = 0;  // in the record
  nlohmann::json min, max;
};

struct PEntry {
  int type = 0, mask = 0;
  uint32_t numPoints = 0;
  uint64_t byteOffset = 0, byteSize = 0;
};

struct PDataset {
  nlohmann::json meta;
  std::vector<PAttribute> attributes;
  size_t stride = 0;
  std::map<std::string, PEntry> nodes;                // real entries by name
  std::vector<std::pair<uint64_t, uint64_t>> chunks;  // (offset, size) in hierarchy.bin
  size_t proxies = 0;
  int maxProxyNesting = 0;  // chunks reached through proxies inside proxy chunks
  std::vector<uint8_t> hierarchy, octree;

  const PAttribute* attribute(const std::string& name) const {
    for (const auto& a : attributes)
      if (a.name == name) return &a;
    return nullptr;
  }
};

template <typename T>
T le(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);  // the test machine is little endian, as is the format
  return v;
}

std::vector<uint8_t> slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), {});
}

int typeSize(const std::string& t) {
  static const std::map<std::string, int> sizes = {
      {"int8", 1},   {"uint8", 1}, {"int16", 2},  {"uint16", 2}, {"int32", 4},
      {"uint32", 4}, {"int64", 8}, {"uint64", 8}, {"float", 4},  {"double", 8}};
  auto it = sizes.find(t);
  return it == sizes.end() ? -1 : it->second;
}

// Loads the dataset; every departure from the format goes into `problems`.
PDataset loadPotree(const fs::path& dir, std::vector<std::string>& problems) {
  auto fail = [&](const std::string& s) { problems.push_back(s); };
  PDataset d;
  {
    std::ifstream f(dir / "metadata.json");
    if (!f) {
      fail("no metadata.json");
      return d;
    }
    d.meta = nlohmann::json::parse(f);
  }
  d.hierarchy = slurp(dir / "hierarchy.bin");
  d.octree = slurp(dir / "octree.bin");
  const auto& m = d.meta;
  if (m.value("version", "") != "2.0") fail("version is not 2.0");
  if (m.value("encoding", "") != "DEFAULT") fail("encoding is not DEFAULT");
  for (const char* k : {"name", "description", "points", "projection", "hierarchy", "offset",
                        "scale", "spacing", "boundingBox", "attributes"})
    if (!m.contains(k)) fail(std::string("metadata lacks ") + k);
  if (!problems.empty()) return d;

  for (const auto& a : m["attributes"]) {
    PAttribute pa;
    pa.name = a["name"];
    pa.type = a["type"];
    pa.size = a["size"];
    pa.numElements = a["numElements"];
    pa.elementSize = a["elementSize"];
    pa.min = a["min"];
    pa.max = a["max"];
    pa.offset = d.stride;
    if (!a.contains("description")) fail(pa.name + ": no description");
    if (typeSize(pa.type) != pa.elementSize)
      fail(pa.name + ": elementSize does not match type " + pa.type);
    if (pa.size != pa.numElements * pa.elementSize)
      fail(pa.name + ": size != numElements * elementSize");
    if (!pa.min.is_array() || int(pa.min.size()) != pa.numElements || !pa.max.is_array() ||
        int(pa.max.size()) != pa.numElements)
      fail(pa.name + ": min/max are not arrays of numElements");
    d.stride += size_t(pa.size);
    d.attributes.push_back(pa);
  }
  if (d.attributes.empty() || d.attributes[0].name != "position" ||
      d.attributes[0].type != "int32" || d.attributes[0].numElements != 3)
    fail("the first attribute is not position int32 x3");

  // The hierarchy, chunk by chunk.
  const uint64_t first = m["hierarchy"]["firstChunkSize"];
  const int step = m["hierarchy"]["stepSize"];
  struct Pending {
    std::string name;
    uint64_t offset, size;
    PEntry proxy;
    int nesting;
  };
  std::vector<Pending> todo = {{"r", 0, first, PEntry{}, 0}};
  while (!todo.empty()) {
    Pending c = todo.back();
    todo.pop_back();
    if (c.size == 0 || c.size % 22 != 0 || c.offset + c.size > d.hierarchy.size()) {
      fail("chunk " + c.name + " at " + std::to_string(c.offset) + "+" + std::to_string(c.size) +
           " is empty, not a multiple of 22 bytes or beyond hierarchy.bin");
      continue;
    }
    d.chunks.emplace_back(c.offset, c.size);
    d.maxProxyNesting = std::max(d.maxProxyNesting, c.nesting);
    const size_t count = c.size / 22;
    std::vector<std::string> names = {c.name};
    for (size_t i = 0; i < count; ++i) {
      if (i >= names.size()) {
        fail("chunk " + c.name + " holds more entries than its child masks announce");
        break;
      }
      const uint8_t* p = &d.hierarchy[c.offset + 22 * i];
      PEntry e{p[0], p[1], le<uint32_t>(p + 2), le<uint64_t>(p + 6), le<uint64_t>(p + 14)};
      const std::string name = names[i];  // a copy: names grows below
      const int depth = int(name.size() - c.name.size());
      if (depth > step) fail(name + ": deeper than stepSize in chunk " + c.name);
      if (e.type > 2) fail(name + ": unknown type " + std::to_string(e.type));
      if (i == 0 && c.name != "r" && (e.numPoints != c.proxy.numPoints || e.mask != c.proxy.mask))
        fail(name + ": its proxy's point count or child mask differs from its real entry");
      if (e.type == 2) {
        if (i == 0) fail(name + ": chunk starts with a proxy");
        if (depth != step) fail(name + ": proxy not stepSize levels below its chunk root");
        ++d.proxies;
        todo.push_back({name, e.byteOffset, e.byteSize, e, c.nesting + 1});
        continue;
      }
      if (e.type == 0 && e.mask == 0) fail(name + ": normal node without children");
      if (e.type == 1 && e.mask != 0) fail(name + ": leaf with children");
      if (!d.nodes.emplace(name, e).second) fail(name + ": listed twice");
      for (int k = 0; k < 8; ++k)
        if (e.mask & (1 << k)) names.push_back(name + char('0' + k));
    }
    if (names.size() != count)
      fail("chunk " + c.name + ": " + std::to_string(count) + " entries for " +
           std::to_string(names.size()) + " announced nodes");
  }
  // Chunks tile hierarchy.bin: the root chunk first, no gap, no overlap.
  auto tiles = [&](std::vector<std::pair<uint64_t, uint64_t>> r, uint64_t fileSize,
                   const std::string& what) {
    std::sort(r.begin(), r.end());
    uint64_t at = 0;
    for (auto [o, s] : r) {
      if (o != at)
        fail(what + ": range at " + std::to_string(o) + " but previous ended at " +
             std::to_string(at));
      at = std::max(at, o + s);
    }
    if (at != fileSize)
      fail(what + ": ranges end at " + std::to_string(at) + ", file has " +
           std::to_string(fileSize));
  };
  tiles(d.chunks, d.hierarchy.size(), "hierarchy.bin");
  if (!d.chunks.empty() && !(d.chunks[0].first == 0 && d.chunks[0].second == first))
    fail("root chunk not at 0");

  // Node payloads tile octree.bin, each exactly numPoints records.
  std::vector<std::pair<uint64_t, uint64_t>> payloads;
  for (const auto& [name, e] : d.nodes) {
    if (e.byteSize != uint64_t(e.numPoints) * d.stride)
      fail(name + ": byteSize is not numPoints * record size");
    if (e.byteOffset + e.byteSize > d.octree.size()) fail(name + ": payload beyond octree.bin");
    if (e.byteSize) payloads.emplace_back(e.byteOffset, e.byteSize);
  }
  tiles(payloads, d.octree.size(), "octree.bin");
  // Child masks name exactly the nodes there are.
  for (const auto& [name, e] : d.nodes) {
    for (int k = 0; k < 8; ++k)
      if (bool(e.mask & (1 << k)) != bool(d.nodes.count(name + char('0' + k))))
        fail(name + ": child mask bit " + std::to_string(k) + " disagrees with the nodes listed");
    if (name != "r" && !d.nodes.count(name.substr(0, name.size() - 1))) fail(name + ": no parent");
  }
  uint64_t total = 0;
  for (const auto& [name, e] : d.nodes) total += e.numPoints;
  if (total != m["points"].get<uint64_t>()) fail("metadata points differ from the nodes' sum");
  int depth = 0;
  for (const auto& [name, e] : d.nodes) depth = std::max(depth, int(name.size()) - 1);
  if (depth != m["hierarchy"]["depth"].get<int>())
    fail("hierarchy depth is not the deepest node's level");
  return d;
}

// Record `i` of node `e`.
const uint8_t* record(const PDataset& d, const PEntry& e, size_t i) {
  return &d.octree[e.byteOffset + i * d.stride];
}

// ---------------------------------------------------------------------------------------------
// Our side: octrees to export, and the expected mapping of their attributes.
// ---------------------------------------------------------------------------------------------
uint16_t liftedRgb(uint16_t v) {
  return v >= 1 && v <= 255 ? 256 : v;
}

struct Expect {
  std::string ours;                 // attribute name in the octree (or layer name)
  std::vector<std::string> potree;  // Potree attribute name(s)
  std::string type;                 // Potree type
  int numElements;                  // per Potree attribute
  enum { Bytes, Rgb, U64ToDouble, Layer } how = Bytes;
};

// A deep octree of hand-made nodes (OctreeWriter directly): every attribute kind the exporter
// maps, a chain of nodes down to `maxDepth`, some empty inner nodes, dark 16-bit colours.
Metadata writeHandBuilt(const fs::path& dir, uint32_t maxDepth, uint64_t seed,
                        uint64_t* darkComponents) {
  PointLayout l;
  l.add({"rgb", ScalarType::U16, 3, ""});
  l.add({"intensity", ScalarType::U16, 1, ""});
  l.add({"classification", ScalarType::U8, 1, ""});
  l.add({"gps_time", ScalarType::F64, 1, ""});
  l.add({"return_number", ScalarType::U8, 1, ""});
  l.add({"number_of_returns", ScalarType::U8, 1, ""});
  l.add({"point_source_id", ScalarType::U16, 1, ""});
  l.add({"normal", ScalarType::F32, 3, ""});
  l.add({"reflectance", ScalarType::I16, 1, "a property no viewer knows"});
  l.add({"wavepacket_offset", ScalarType::U64, 1, ""});
  const uint32_t cubeSize = 1u << 16;
  Metadata meta;
  meta.offset = {500000.25, 5000000.5, 100.125};
  meta.scale = {0.001, 0.001, 0.001};
  meta.cubeSize = cubeSize;
  meta.spacing = 0.5;
  meta.layout = l;
  meta.rgbSourceBits = 16;
  meta.generator = "potree_export_test";
  std::mt19937_64 rng(seed);
  OctreeWriter w(dir, l, Codec::Zstd, true);
  uint64_t total = 0, dark = 0;
  Box3d bounds;
  std::function<void(const NodeKey&)> visit = [&](const NodeKey& k) {
    uint8_t mask = 0;
    if (k.level < maxDepth) {
      const bool spine =
          k.x == (1u << k.level) - 1 && k.y == 0 && k.z == (1u << k.level) - 1;  // r, r5, r55, ...
      if (spine) mask |= 1 << 5;
      for (int c = 0; c < 8; ++c)
        if (int(rng() % 100) < (k.level < 2 ? 50 : 15)) mask |= uint8_t(1 << c);
    }
    const size_t n = (mask && rng() % 4 == 0) ? 0 : 1 + rng() % 25;
    PointBuffer p(l.stride());
    const uint32_t side = cubeSize >> k.level;
    std::vector<std::pair<uint64_t, std::vector<uint8_t>>> pts;
    for (size_t i = 0; i < n; ++i) {
      uint32_t rel[3] = {uint32_t(rng() % side), uint32_t(rng() % side), uint32_t(rng() % side)};
      std::vector<uint8_t> a(l.stride());
      uint8_t* q = a.data();
      for (int c = 0; c < 3; ++c) {
        uint16_t v = rng() % 3 == 0 ? uint16_t(rng() % 256) : uint16_t(rng());
        if (i == 0 && c == 0) v = 0;
        dark += v >= 1 && v <= 255;
        std::memcpy(q + 2 * c, &v, 2);
      }
      const uint16_t intensity = uint16_t(rng());
      const uint8_t cls = uint8_t(rng() % 32), rn = uint8_t(1 + rng() % 5),
                    nr = uint8_t(5 + rng() % 3);
      const double gps = 3e8 + double(rng() % 1000000000) * 1e-6;
      const uint16_t psid = uint16_t(rng());
      float nrm[3] = {float(int(rng() % 200) - 100), float(int(rng() % 200) - 100), 1.0f};
      const float len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
      for (float& x : nrm) x /= len;
      const int16_t refl = int16_t(rng());
      const uint64_t wpo = rng() >> 20;
      size_t at = 6;
      std::memcpy(q + at, &intensity, 2), at += 2;
      std::memcpy(q + at, &cls, 1), at += 1;
      std::memcpy(q + at, &gps, 8), at += 8;
      std::memcpy(q + at, &rn, 1), at += 1;
      std::memcpy(q + at, &nr, 1), at += 1;
      std::memcpy(q + at, &psid, 2), at += 2;
      std::memcpy(q + at, nrm, 12), at += 12;
      std::memcpy(q + at, &refl, 2), at += 2;
      std::memcpy(q + at, &wpo, 8), at += 8;
      EXPECT_EQ(at, l.stride());
      std::vector<uint8_t> rec(12);
      std::memcpy(rec.data(), rel, 12);
      rec.insert(rec.end(), a.begin(), a.end());
      pts.emplace_back(mortonEncode21(rel[0], rel[1], rel[2]), rec);
      bounds.extend(meta.world(0, double(uint64_t(k.x) * side + rel[0])),
                    meta.world(1, double(uint64_t(k.y) * side + rel[1])),
                    meta.world(2, double(uint64_t(k.z) * side + rel[2])));
    }
    std::stable_sort(pts.begin(), pts.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [code, rec] : pts) {
      uint32_t rel[3];
      std::memcpy(rel, rec.data(), 12);
      p.push(rel, rec.data() + 12);
    }
    w.writeNode(k, p);
    total += n;
    for (int c = 0; c < 8; ++c)
      if (mask & (1 << c)) visit(k.child(c));
  };
  visit(NodeKey::root());
  meta.points = total;
  meta.bounds = bounds;
  meta.accounting.input = meta.accounting.kept = total;
  w.finish(meta);
  if (darkComponents) *darkComponents = dark;
  return meta;
}

std::vector<Expect> handBuiltMapping() {
  return {{"rgb", {"rgb"}, "uint16", 3, Expect::Rgb},
          {"intensity", {"intensity"}, "uint16", 1},
          {"classification", {"classification"}, "uint8", 1},
          {"gps_time", {"gps-time"}, "double", 1},
          {"return_number", {"return number"}, "uint8", 1},
          {"number_of_returns", {"number of returns"}, "uint8", 1},
          {"point_source_id", {"point source id"}, "uint16", 1},
          {"normal", {"NormalX", "NormalY", "NormalZ"}, "float", 1},
          {"reflectance", {"reflectance"}, "int16", 1},
          {"wavepacket_offset", {"wavepacket_offset"}, "double", 1, Expect::U64ToDouble},
          {"hdr", {"hdr"}, "float", 3, Expect::Layer}};
}

// Compares the dataset with the octree, node by node and point by point.
void compareWithOctree(const PDataset& d, const fs::path& octreeDir,
                       const std::vector<Expect>& mapping, std::vector<std::string>& problems) {
  auto fail = [&](const std::string& s) {
    if (problems.size() < 50) problems.push_back(s);
  };
  OctreeReader r(octreeDir);
  const Metadata& m = r.metadata();
  const auto& j = d.meta;
  // Frame: our offset and scale, and our root cube as the bounding box.
  for (int a = 0; a < 3; ++a) {
    if (j["offset"][a].get<double>() != m.offset[a])
      fail("offset differs on axis " + std::to_string(a));
    if (j["scale"][a].get<double>() != m.scale[a])
      fail("scale differs on axis " + std::to_string(a));
  }
  // The bounding box is the octree's root cube: min the grid's origin, max = min + cube edge
  // (edges equal up to the rounding of the corner coordinates).
  const auto& bb = j["boundingBox"];
  for (int a = 0; a < 3; ++a) {
    const double edge = m.cubeSize * m.scale[a];
    const double lo = bb["min"][a].get<double>(), hi = bb["max"][a].get<double>();
    if (lo != m.offset[a]) fail("bounding box min is not the octree's cube corner");
    if (hi != lo + edge) fail("bounding box max is not min + the octree's cube edge");
    const double tol =
        4 * std::numeric_limits<double>::epsilon() * std::max(std::abs(lo), std::abs(hi));
    if (std::abs((hi - lo) - edge) > tol) fail("bounding box is not a cube");
  }
  if (j["points"].get<uint64_t>() != m.points) fail("metadata points differ from the octree's");
  if (j["hierarchy"]["depth"].get<uint32_t>() != m.depth) fail("depth differs");

  std::map<std::string, std::unique_ptr<ColourLayerReader>> layers;
  for (const auto& l : m.layers)
    layers[l.name] = std::make_unique<ColourLayerReader>(octreeDir, m, l.name);

  const PAttribute* pos = d.attribute("position");
  double posMin[3] = {INFINITY, INFINITY, INFINITY}, posMax[3] = {-INFINITY, -INFINITY, -INFINITY};
  std::map<std::string, std::pair<double, double>>
      seen;  // first element's range per Potree attribute
  std::set<std::string> ourNames;
  for (const auto& [key, entry] : r.allNodes()) {
    const std::string name = key.name();
    ourNames.insert(name);
    auto it = d.nodes.find(name);
    if (it == d.nodes.end()) {
      fail("node " + name + " is missing from the Potree hierarchy");
      continue;
    }
    const PEntry& e = it->second;
    if (e.numPoints != entry.numPoints) fail(name + ": point count differs");
    if (e.mask != entry.childMask) fail(name + ": child mask differs");
    if (e.numPoints != entry.numPoints) continue;
    PointBuffer pts = r.readNode(key);
    std::map<std::string, std::vector<float>> layerRgb;
    for (auto& [ln, lr] : layers) layerRgb[ln] = lr->readNode(key, entry.numPoints);
    for (size_t i = 0; i < pts.size(); ++i) {
      const uint8_t* rec = record(d, e, i);
      for (int a = 0; a < 3; ++a) {
        const int32_t q = le<int32_t>(rec + pos->offset + 4 * a);
        if (int64_t(q) != int64_t(pts.pos[3 * i + a])) {
          fail(name + " point " + std::to_string(i) + ": integer position differs");
          break;
        }
        const double world = q * j["scale"][a].get<double>() + j["offset"][a].get<double>();
        if (world != pts.pos[3 * i + a] * m.scale[a] + m.offset[a])
          fail(name + ": world position differs");
        if (world < bb["min"][a].get<double>() || world > bb["max"][a].get<double>())
          fail(name + ": point outside the bounding box");
        posMin[a] = std::min(posMin[a], world), posMax[a] = std::max(posMax[a], world);
      }
      const uint8_t* ours = pts.attrsOf(i);
      for (const auto& x : mapping) {
        const int li = m.layout.find(x.ours);
        if (x.how != Expect::Layer && li < 0) {
          fail("test mapping names " + x.ours + ", which the octree lacks");
          return;
        }
        for (size_t k = 0; k < x.potree.size(); ++k) {
          const PAttribute* pa = d.attribute(x.potree[k]);
          if (!pa) {
            fail("no Potree attribute " + x.potree[k] + " for " + x.ours);
            return;
          }
          if (pa->type != x.type || pa->numElements != x.numElements) {
            fail(pa->name + ": type " + pa->type + " x" + std::to_string(pa->numElements) +
                 ", expected " + x.type);
            return;
          }
          const uint8_t* theirs = rec + pa->offset;
          bool same = true;
          if (x.how == Expect::Layer) {
            same = std::memcmp(theirs, &layerRgb[x.ours][3 * i], 12) == 0;
          } else {
            const uint8_t* src = ours + m.layout.offset(size_t(li)) + k * size_t(pa->size);
            if (x.how == Expect::Bytes) {
              same = std::memcmp(theirs, src, size_t(pa->size)) == 0;
            } else if (x.how == Expect::Rgb) {
              for (int c = 0; c < 3; ++c)
                same &= le<uint16_t>(theirs + 2 * c) == liftedRgb(le<uint16_t>(src + 2 * c));
            } else {
              same = le<double>(theirs) == double(le<uint64_t>(src));
            }
          }
          if (!same)
            fail(name + " point " + std::to_string(i) + ": " + pa->name + " differs from " +
                 x.ours);
          // The first element's range, as the type reads it.
          double v = 0;
          if (pa->type == "uint8")
            v = theirs[0];
          else if (pa->type == "uint16")
            v = le<uint16_t>(theirs);
          else if (pa->type == "int16")
            v = le<int16_t>(theirs);
          else if (pa->type == "float")
            v = le<float>(theirs);
          else if (pa->type == "double")
            v = le<double>(theirs);
          auto [sit, fresh] = seen.emplace(pa->name, std::pair{v, v});
          if (!fresh)
            sit->second = {std::min(sit->second.first, v), std::max(sit->second.second, v)};
        }
      }
    }
  }
  for (const auto& [name, e] : d.nodes)
    if (!ourNames.count(name)) fail("Potree node " + name + " is not in the octree");
  // Attribute ranges in metadata.json are those of the points.
  if (m.points) {
    for (int a = 0; a < 3; ++a)
      if (pos->min[a].get<double>() != posMin[a] || pos->max[a].get<double>() != posMax[a])
        fail("position min/max are not the points' bounds on axis " + std::to_string(a));
    for (const auto& [name, range] : seen) {
      const PAttribute* pa = d.attribute(name);
      if (pa->min[0].get<double>() != range.first || pa->max[0].get<double>() != range.second)
        fail(name + ": metadata min/max differ from the points' range");
    }
  }
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += "\n  " + x;
  return s;
}

PotreeExportOptions quiet(uint32_t step = 4) {
  PotreeExportOptions o;
  o.progress = ProgressMode::Quiet;
  o.stepSize = step;
  o.threads = 2;
  return o;
}

}  // namespace

TEST(PotreeExport, HandBuiltOctreeRoundTripsAtEveryStepSize) {
  TempDir t;
  uint64_t dark = 0;
  const Metadata meta = writeHandBuilt(t.path() / "o", 7, 11, &dark);
  ASSERT_GE(meta.depth, 7u);
  ASSERT_GT(dark, 0u);
  test::writeColourLayer(t.path() / "o", "hdr", [](const NodeKey& k, size_t i) {
    return std::array<float, 3>{float(k.level) * 0.5f, float(i % 7), 2.0f};
  });
  for (uint32_t step : {4u, 2u, 1u}) {
    SCOPED_TRACE("stepSize " + std::to_string(step));
    const fs::path out = t.path() / ("p" + std::to_string(step));
    PotreeExportReport rep = exportPotree(t.path() / "o", out, quiet(step));
    EXPECT_EQ(rep.points, meta.points);
    EXPECT_EQ(rep.rgbLifted, dark);
    std::vector<std::string> problems;
    PDataset d = loadPotree(out, problems);
    ASSERT_TRUE(problems.empty()) << joined(problems);
    EXPECT_EQ(d.meta["hierarchy"]["stepSize"].get<uint32_t>(), step);
    EXPECT_GE(d.proxies, 1u);
    EXPECT_EQ(d.chunks.size(), d.proxies + 1);
    // Depth 7: proxies within proxy chunks for the small steps.
    if (step <= 2) {
      EXPECT_GE(d.maxProxyNesting, 2);
    }
    EXPECT_EQ(d.nodes.size(), meta.nodes);
    compareWithOctree(d, t.path() / "o", handBuiltMapping(), problems);
    EXPECT_TRUE(problems.empty()) << joined(problems);
  }
}

TEST(PotreeExport, BuiltScanRoundTrips) {
  // The converter's own output: 8-bit colour stored as v * 257 (nothing to lift), intensity,
  // normals, national-grid coordinates.
  TempDir t;
  SyntheticSpec spec;
  spec.points = 30000;
  spec.normals = true;
  spec.origin = {500000, 5000000, 100};
  spec.size = 40;
  BuildOptions o;
  o.output = t.path() / "o";
  o.progress = ProgressMode::Quiet;
  o.threads = 2;
  o.maxNodePoints = 500;
  std::vector<std::unique_ptr<PointReader>> readers;
  readers.push_back(openSynthetic(spec));
  buildOctree(std::move(readers), o);
  PotreeExportReport rep = exportPotree(o.output, t.path() / "p", quiet(2));
  EXPECT_EQ(rep.points, spec.points);
  EXPECT_EQ(rep.rgbLifted, 0u);
  std::vector<std::string> problems;
  PDataset d = loadPotree(t.path() / "p", problems);
  ASSERT_TRUE(problems.empty()) << joined(problems);
  EXPECT_GE(d.proxies, 1u);
  EXPECT_EQ(d.meta["points"].get<uint64_t>(), spec.points);
  compareWithOctree(
      d, o.output,
      {{"rgb", {"rgb"}, "uint16", 3, Expect::Bytes},  // exact: 8-bit colour is never lifted
       {"intensity", {"intensity"}, "uint16", 1},
       {"normal", {"NormalX", "NormalY", "NormalZ"}, "float", 1}},
      problems);
  EXPECT_TRUE(problems.empty()) << joined(problems);
  EXPECT_EQ(d.attributes.size(), 6u);  // position, rgb, intensity, NormalX..Z
}

TEST(PotreeExport, TheReaderHereCatchesDamage) {
  // The checks above can fail: damage an export in ways a viewer would trip over.
  TempDir t;
  writeHandBuilt(t.path() / "o", 5, 3, nullptr);
  const fs::path out = t.path() / "p";
  exportPotree(t.path() / "o", out, quiet(2));
  // No colour layer in this octree: leave it out of the mapping.
  auto mapping = handBuiltMapping();
  mapping.pop_back();
  auto problemsAfter =
      [&](const std::function<void(std::vector<uint8_t>&, std::vector<uint8_t>&)>& damage) {
        const auto h0 = slurp(out / "hierarchy.bin"), o0 = slurp(out / "octree.bin");
        auto h = h0, o = o0;
        damage(h, o);
        test::writeFile((out / "hierarchy.bin").string(), std::string(h.begin(), h.end()));
        test::writeFile((out / "octree.bin").string(), std::string(o.begin(), o.end()));
        std::vector<std::string> problems;
        PDataset d = loadPotree(out, problems);
        if (problems.empty()) compareWithOctree(d, t.path() / "o", mapping, problems);
        test::writeFile((out / "hierarchy.bin").string(), std::string(h0.begin(), h0.end()));
        test::writeFile((out / "octree.bin").string(), std::string(o0.begin(), o0.end()));
        return problems;
      };
  // Undamaged.
  {
    std::vector<std::string> problems;
    PDataset d = loadPotree(out, problems);
    compareWithOctree(d, t.path() / "o", mapping, problems);
    EXPECT_TRUE(problems.empty()) << joined(problems);
  }
  // A proxy pointing one entry off.
  EXPECT_FALSE(problemsAfter([](auto& h, auto&) {
                 for (size_t i = 0; i + 22 <= h.size(); i += 22)
                   if (h[i] == 2) {
                     h[i + 6] += 22;
                     break;
                   }
               }).empty());
  // A child mask bit dropped from the root.
  EXPECT_FALSE(problemsAfter([](auto& h, auto&) { h[1] &= uint8_t(h[1] - 1); }).empty());
  // One flipped position byte.
  EXPECT_FALSE(problemsAfter([](auto&, auto& o) { o[1] ^= 0x40; }).empty());
  // A point count off by one.
  EXPECT_FALSE(problemsAfter([](auto& h, auto&) { h[2] += 1; }).empty());
}

TEST(PotreeExport, RefusesNonEmptyDirectoryTheOctreeAndFiles) {
  TempDir t;
  writeHandBuilt(t.path() / "o", 3, 5, nullptr);
  fs::create_directories(t.path() / "busy");
  test::writeFile(t.file("busy/keep.txt"), "mine");
  Error e = test::errorOf([&] { exportPotree(t.path() / "o", t.path() / "busy", quiet()); });
  EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  EXPECT_FALSE(fs::exists(t.path() / "busy" / "metadata.json"));
  // With overwrite: written beside the other file, which stays.
  PotreeExportOptions o = quiet();
  o.overwrite = true;
  exportPotree(t.path() / "o", t.path() / "busy", o);
  EXPECT_TRUE(fs::exists(t.path() / "busy" / "metadata.json"));
  EXPECT_EQ(test::readFile(t.file("busy/keep.txt")), "mine");
  // Never into the octree itself, not even with overwrite.
  e = test::errorOf([&] { exportPotree(t.path() / "o", t.path() / "o", o); });
  EXPECT_NE(std::string(e.what()).find("octree"), std::string::npos) << e.what();
  EXPECT_TRUE(fs::exists(t.path() / "o" / "metadata.json"));
  // A file is not a directory.
  test::writeFile(t.file("file"), "x");
  e = test::errorOf([&] { exportPotree(t.path() / "o", t.path() / "file", o); });
  EXPECT_NE(std::string(e.what()).find("not a directory"), std::string::npos) << e.what();
}

TEST(PotreeExport, CommandLine) {
  TempDir t;
  writeHandBuilt(t.path() / "o", 3, 7, nullptr);
  const std::string oct = t.file("o");
  std::string out;
  // No extension: potree.
  ASSERT_EQ(runCli("export " + oct + " -o " + t.file("web") + " --progress quiet", &out), 0) << out;
  EXPECT_TRUE(fs::exists(t.path() / "web" / "hierarchy.bin"));
  EXPECT_NE(out.find("gps_time"), std::string::npos) << out;  // the mapping is reported
  std::vector<std::string> problems;
  loadPotree(t.path() / "web", problems);
  EXPECT_TRUE(problems.empty()) << joined(problems);
  // Again into the now non-empty directory: refused, then forced.
  EXPECT_NE(runCli("export " + oct + " -o " + t.file("web") + " --progress quiet", &out), 0);
  EXPECT_NE(out.find("--force"), std::string::npos) << out;
  EXPECT_EQ(runCli("export " + oct + " -o " + t.file("web") + " --force --progress quiet", &out), 0)
      << out;
  // An explicit format with any name.
  EXPECT_EQ(
      runCli("export " + oct + " --format potree -o " + t.file("x.potree") + " --progress quiet",
             &out),
      0)
      << out;
  EXPECT_TRUE(fs::exists(t.path() / "x.potree" / "metadata.json"));
  // Unknown format, unknown extension, --level with potree, a mismatched extension.
  EXPECT_NE(runCli("export " + oct + " --format copc -o " + t.file("c"), &out), 0);
  EXPECT_NE(out.find("copc"), std::string::npos) << out;
  EXPECT_NE(runCli("export " + oct + " -o " + t.file("a.xyz"), &out), 0);
  EXPECT_NE(out.find("--format"), std::string::npos) << out;
  EXPECT_NE(runCli("export " + oct + " --level 1 -o " + t.file("lvl"), &out), 0);
  EXPECT_NE(out.find("--level"), std::string::npos) << out;
  EXPECT_NE(runCli("export " + oct + " --format las -o " + t.file("a.ply"), &out), 0);
  // LAS still works, and help explains potree.
  EXPECT_EQ(runCli("export " + oct + " -o " + t.file("all.las"), &out), 0) << out;
  EXPECT_EQ(runCli("export --help", &out), 0);
  EXPECT_NE(out.find("potree"), std::string::npos) << out;
  EXPECT_NE(out.find("--force"), std::string::npos) << out;
}
