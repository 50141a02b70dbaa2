#include "nestlight/converters/potree_export.h"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/octree_writer.h"
#include "nestlight/octree/staged_directory.h"
#include "readers/las_format.h"

namespace nestlight {
namespace fs = std::filesystem;

namespace {

// hierarchy.bin entry: u8 type, u8 child mask, u32 points, u64 byte offset, u64 byte size.
constexpr size_t kEntryBytes = 22;
constexpr size_t kEntryOffsetField = 6;  // where byte offset and byte size start
constexpr uint8_t kTypeNormal = 0, kTypeLeaf = 1, kTypeProxy = 2;
constexpr size_t kPositionBytes = 12;  // int32 x, y, z

// Potree's names for the LAS fields we keep under LAS names (PotreeConverter writes LAS fields
// with spaces: "return number", "point source id"; GPS time is "gps-time").
std::string potreeName(const std::string& name) {
  if (name == las::kGpsTime) return "gps-time";
  static const char* const kSpaced[] = {
      las::kReturnNumber,     las::kNumberOfReturns,     las::kScanDirection,
      las::kEdgeOfFlightLine, las::kClassificationFlags, las::kScannerChannel,
      las::kScanAngleRank,    las::kScanAngle,           las::kUserData,
      las::kPointSourceId};
  for (const char* s : kSpaced) {
    if (name == s) {
      std::string out = name;
      std::replace(out.begin(), out.end(), '_', ' ');
      return out;
    }
  }
  return name;
}

enum class Conversion {
  Copy,      // the bytes as stored
  ToDouble,  // 64-bit integers: the viewer's decoder has no 64-bit integer reader
  Rgb,       // uint16 x3, components 1..255 raised to 256 (see liftRgb)
};

// One Potree attribute and where its bytes come from.
struct OutAttribute {
  std::string name, description;
  ScalarType type = ScalarType::U8;  // as written
  uint32_t elements = 1;
  Conversion conversion = Conversion::Copy;
  int layer = -1;           // -1: from the payload's attribute record; else colour layer index
  size_t sourceOffset = 0;  // byte offset in the attribute record (or in the layer's 12 bytes)
  ScalarType sourceType = ScalarType::U8;
  size_t size() const { return scalarSize(type) * elements; }
};

// The Potree viewer reads colour as uint16 and takes a component above 255 as 16-bit (divided
// by 256) and one of 0..255 as 8-bit. Our rgb is always 16-bit (8-bit sources are stored as
// v * 257, never in 1..255), so a dark 16-bit component of 1..255 would be shown as bright as
// 255/255. It is written as 256 instead: shown as 1/255, a change below 256/65535 of full scale.
inline uint16_t liftRgb(uint16_t v) {
  return (v >= 1 && v <= 255) ? uint16_t(256) : v;
}

struct MinMax {
  std::vector<double> min, max;  // one per element of every attribute, position first
  void init(size_t n) {
    min.assign(n, std::numeric_limits<double>::infinity());
    max.assign(n, -std::numeric_limits<double>::infinity());
  }
  void merge(const MinMax& o) {
    for (size_t i = 0; i < min.size(); ++i) {
      min[i] = std::min(min[i], o.min[i]);
      max[i] = std::max(max[i], o.max[i]);
    }
  }
};

void pwriteAll(int fd, const void* data, size_t size, uint64_t offset, const fs::path& path) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    ssize_t n = ::pwrite(fd, p, size, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw Error(path.string(), Error::atByte(offset),
                  std::string("write failed: ") + std::strerror(errno));
    p += n;
    size -= static_cast<size_t>(n);
    offset += static_cast<uint64_t>(n);
  }
}

void put8(uint8_t* p, uint8_t v) {
  p[0] = v;
}
void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}
void put64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = uint8_t(v >> (8 * i));
}

// The temporary output files; removed unless committed.
class OutputFiles {
 public:
  explicit OutputFiles(const fs::path& dir)
      : octreeTmp_(dir / "octree.bin.tmp"), hierarchyTmp_(dir / "hierarchy.bin.tmp") {
    octreeFd_ = openFile(octreeTmp_);
    hierarchyFd_ = openFile(hierarchyTmp_);
  }
  ~OutputFiles() {
    closeAll();
    if (!committed_) {
      std::error_code ec;
      fs::remove(octreeTmp_, ec);
      fs::remove(hierarchyTmp_, ec);
    }
  }
  int octreeFd() const { return octreeFd_; }
  int hierarchyFd() const { return hierarchyFd_; }
  const fs::path& octreePath() const { return octreeTmp_; }
  const fs::path& hierarchyPath() const { return hierarchyTmp_; }

  // Makes the data durable and renames the files into place.
  void commit(const fs::path& dir) {
    for (auto [fd, path] :
         {std::pair{octreeFd_, octreeTmp_}, std::pair{hierarchyFd_, hierarchyTmp_}})
      if (::fsync(fd) != 0)
        throw Error(path.string(), "", std::string("fsync failed: ") + std::strerror(errno));
    closeAll();
    fs::rename(octreeTmp_, dir / "octree.bin");
    fs::rename(hierarchyTmp_, dir / "hierarchy.bin");
    committed_ = true;
  }

 private:
  static int openFile(const fs::path& p) {
    int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(p.string(), "", std::string("cannot create: ") + std::strerror(errno));
    return fd;
  }
  void closeAll() {
    if (octreeFd_ >= 0) ::close(octreeFd_);
    if (hierarchyFd_ >= 0) ::close(hierarchyFd_);
    octreeFd_ = hierarchyFd_ = -1;
  }
  fs::path octreeTmp_, hierarchyTmp_;
  int octreeFd_ = -1, hierarchyFd_ = -1;
  bool committed_ = false;
};

// Builds the Potree attribute list for our layout (and colour layers), with unique names.
std::vector<OutAttribute> mapAttributes(const Metadata& m,
                                        std::vector<PotreeAttributeMapping>& report) {
  std::vector<OutAttribute> out;
  std::set<std::string> used = {"position"};
  auto unique = [&](const std::string& wanted, const std::string& fallback) {
    std::string name = used.count(wanted) ? fallback : wanted;
    for (int k = 2; used.count(name); ++k) name = fallback + "_" + std::to_string(k);
    used.insert(name);
    return name;
  };
  const PointLayout& l = m.layout;
  for (size_t i = 0; i < l.size(); ++i) {
    const Attribute& a = l[i];
    PotreeAttributeMapping rep;
    rep.source = a.name;
    if (a.name == attr::kNormal && a.type == ScalarType::F32 && a.components == 3) {
      // The viewer assembles normals from three float attributes of these names.
      static const char* const kAxes[3] = {"NormalX", "NormalY", "NormalZ"};
      for (uint32_t c = 0; c < 3; ++c) {
        OutAttribute o;
        o.name = unique(kAxes[c], std::string("normal_") + "xyz"[c]);
        o.description = a.description;
        o.type = o.sourceType = ScalarType::F32;
        o.sourceOffset = l.offset(i) + 4 * c;
        out.push_back(o);
        rep.potree.push_back(o.name);
      }
      rep.type = "float";
      rep.note = "split into three float attributes";
      report.push_back(rep);
      continue;
    }
    OutAttribute o;
    o.name = unique(potreeName(a.name), a.name);
    o.description = a.description;
    o.elements = a.components;
    o.sourceOffset = l.offset(i);
    o.sourceType = a.type;
    o.type = a.type;
    if (a.type == ScalarType::U64 || a.type == ScalarType::I64) {
      o.type = ScalarType::F64;
      o.conversion = Conversion::ToDouble;
      rep.note = "64-bit integer written as double (exact up to 2^53)";
    } else if (a.name == attr::kRgb && a.type == ScalarType::U16 && a.components == 3) {
      o.conversion = Conversion::Rgb;
      rep.note = "16-bit components 1..255 written as 256 (the viewer reads 0..255 as 8-bit)";
    }
    out.push_back(o);
    rep.potree.push_back(o.name);
    rep.type = scalarName(o.type);
    report.push_back(rep);
  }
  for (size_t li = 0; li < m.layers.size(); ++li) {
    OutAttribute o;
    o.name = unique(m.layers[li].name, "layer_" + m.layers[li].name);
    o.description = "colour layer '" + m.layers[li].name + "': linear RGB";
    o.type = o.sourceType = ScalarType::F32;
    o.elements = 3;
    o.layer = static_cast<int>(li);
    out.push_back(o);
    report.push_back({"layer " + m.layers[li].name, {o.name}, "float", "colour layer, 3 floats"});
  }
  return out;
}

// One node converted to Potree records.
struct NodeBytes {
  std::vector<uint8_t> bytes;
  MinMax range;
  uint64_t lifted = 0;
};

class Exporter {
 public:
  Exporter(const fs::path& octreeDir, const PotreeExportOptions& o)
      : reader_(octreeDir), meta_(reader_.metadata()), options_(o) {
    attrs_ = mapAttributes(meta_, report_.attributes);
    stride_ = kPositionBytes;
    elements_ = 3;
    for (const auto& a : attrs_) stride_ += a.size(), elements_ += a.elements;
    for (const auto& l : meta_.layers)
      layers_.push_back(std::make_unique<ColourLayerReader>(octreeDir, meta_, l.name));
    range_.init(elements_);
  }

  PotreeExportReport run(const fs::path& outDir, const std::string& name);

 private:
  struct Item {
    NodeKey key;
    HierarchyEntry entry;
    bool proxy = false;
    uint64_t byteOffset = 0, byteSize = 0;
  };
  HierarchyEntry entryOf(const NodeKey& key) {
    auto e = reader_.node(key);
    if (!e)
      throw Error((reader_.dir() / meta_.hierarchyFile).string(), "node " + key.name(),
                  "listed in its parent's child mask but absent");
    return *e;
  }
  NodeBytes convert(const Item& item);
  void writeChunk(const NodeKey& root, uint64_t patchAt,
                  std::deque<std::pair<NodeKey, uint64_t>>& queue);

  OctreeReader reader_;
  const Metadata& meta_;
  PotreeExportOptions options_;
  std::vector<OutAttribute> attrs_;
  std::vector<std::unique_ptr<ColourLayerReader>> layers_;
  size_t stride_ = 0, elements_ = 0;
  MinMax range_;
  PotreeExportReport report_;
  std::unique_ptr<OutputFiles> files_;
  std::unique_ptr<Progress> progress_;
  std::unique_ptr<tbb::task_arena> arena_;
  uint64_t octreeEnd_ = 0, hierarchyEnd_ = 0, firstChunkSize_ = 0;
};

NodeBytes Exporter::convert(const Item& item) {
  NodeBytes out;
  out.range.init(elements_);
  const uint32_t n = item.entry.numPoints;
  if (n == 0) return out;
  PointBuffer pts = reader_.readNode(item.key);
  if (pts.size() != n)
    throw Error(
        (reader_.dir() / meta_.payloadFile).string(), "node " + item.key.name(),
        "decoded " + std::to_string(pts.size()) + " points, its entry says " + std::to_string(n));
  std::vector<std::vector<float>> layerRgb;
  for (const auto& l : layers_) layerRgb.push_back(l->readNode(item.key, n));

  out.bytes.resize(size_t(n) * stride_);
  double* mn = out.range.min.data();
  double* mx = out.range.max.data();
  for (size_t i = 0; i < n; ++i) {
    uint8_t* rec = &out.bytes[i * stride_];
    for (int a = 0; a < 3; ++a) {
      const uint32_t q = pts.pos[3 * i + a];
      // The root cube is at most 2^31 units wide (cubeSize is a uint32 power of two).
      if (q > uint32_t(std::numeric_limits<int32_t>::max()))
        throw Error((reader_.dir() / meta_.payloadFile).string(), "node " + item.key.name(),
                    "position beyond the int32 range of Potree");
      put32(rec + 4 * a, q);
      mn[a] = std::min(mn[a], double(q));
      mx[a] = std::max(mx[a], double(q));
    }
    const uint8_t* src = pts.attrsOf(i);
    size_t at = kPositionBytes, el = 3;
    for (const auto& o : attrs_) {
      const uint8_t* from =
          o.layer >= 0 ? reinterpret_cast<const uint8_t*>(&layerRgb[size_t(o.layer)][3 * i])
                       : src + o.sourceOffset;
      const size_t es = scalarSize(o.type);
      for (uint32_t c = 0; c < o.elements; ++c, ++el) {
        uint8_t* to = rec + at + c * es;
        switch (o.conversion) {
          case Conversion::Copy:
            std::memcpy(to, from + c * es, es);
            break;
          case Conversion::ToDouble: {
            const double v = loadAsDouble(o.sourceType, from + c * scalarSize(o.sourceType));
            std::memcpy(to, &v, 8);
            break;
          }
          case Conversion::Rgb: {
            uint16_t v;
            std::memcpy(&v, from + 2 * c, 2);
            const uint16_t w = liftRgb(v);
            out.lifted += w != v;
            std::memcpy(to, &w, 2);
            break;
          }
        }
        const double v = loadAsDouble(o.type, to);
        mn[el] = std::min(mn[el], v);
        mx[el] = std::max(mx[el], v);
      }
      at += o.size();
    }
  }
  return out;
}

// Writes the chunk rooted at `root` at the end of hierarchy.bin, its nodes' points at the end of
// octree.bin, and then the chunk's location into the proxy entry at `patchAt` (none for the
// root chunk). Its own proxies are queued with the place of their entries.
void Exporter::writeChunk(const NodeKey& root, uint64_t patchAt,
                          std::deque<std::pair<NodeKey, uint64_t>>& queue) {
  const uint32_t step = options_.stepSize;
  std::vector<Item> items;
  items.push_back({root, entryOf(root)});
  // Breadth first, children in index order: the order in which a reader walking the chunk with a
  // queue expects them.
  for (size_t i = 0; i < items.size(); ++i) {
    const Item it = items[i];
    if (it.proxy || it.key.level - root.level >= step) continue;
    for (int c = 0; c < 8; ++c) {
      if (!(it.entry.childMask & (1u << c))) continue;
      Item child{it.key.child(c), entryOf(it.key.child(c))};
      child.proxy = child.key.level - root.level == step && child.entry.childMask != 0;
      items.push_back(child);
    }
  }

  // Points: a window of nodes decoded in parallel, written in order.
  std::vector<size_t> real;
  for (size_t i = 0; i < items.size(); ++i)
    if (!items[i].proxy) real.push_back(i);
  const size_t window = std::max<size_t>(8, 2 * size_t(arena_->max_concurrency()));
  std::vector<NodeBytes> done;
  for (size_t start = 0; start < real.size(); start += window) {
    const size_t count = std::min(window, real.size() - start);
    done.assign(count, {});
    arena_->execute([&] {
      tbb::parallel_for(size_t(0), count,
                        [&](size_t k) { done[k] = convert(items[real[start + k]]); });
    });
    for (size_t k = 0; k < count; ++k) {
      Item& it = items[real[start + k]];
      it.byteOffset = octreeEnd_;
      it.byteSize = done[k].bytes.size();
      pwriteAll(files_->octreeFd(), done[k].bytes.data(), done[k].bytes.size(), octreeEnd_,
                files_->octreePath());
      octreeEnd_ += it.byteSize;
      range_.merge(done[k].range);
      report_.rgbLifted += done[k].lifted;
      report_.points += it.entry.numPoints;
      ++report_.nodes;
      progress_->advance(it.entry.numPoints, it.entry.numPoints);
    }
  }

  const uint64_t chunkOffset = hierarchyEnd_;
  std::vector<uint8_t> chunk(items.size() * kEntryBytes);
  for (size_t i = 0; i < items.size(); ++i) {
    const Item& it = items[i];
    uint8_t* e = &chunk[i * kEntryBytes];
    put8(e + 0, it.proxy ? kTypeProxy : (it.entry.childMask ? kTypeNormal : kTypeLeaf));
    put8(e + 1, it.entry.childMask);
    put32(e + 2, it.entry.numPoints);
    // A proxy's location is its chunk's, patched in when that chunk is written.
    put64(e + 6, it.proxy ? 0 : it.byteOffset);
    put64(e + 14, it.proxy ? 0 : it.byteSize);
    if (it.proxy) {
      queue.emplace_back(it.key, chunkOffset + i * kEntryBytes);
      ++report_.proxies;
    }
  }
  pwriteAll(files_->hierarchyFd(), chunk.data(), chunk.size(), chunkOffset,
            files_->hierarchyPath());
  hierarchyEnd_ += chunk.size();
  if (chunkOffset == 0) firstChunkSize_ = chunk.size();
  if (patchAt != std::numeric_limits<uint64_t>::max()) {
    uint8_t loc[16];
    put64(loc, chunkOffset);
    put64(loc + 8, chunk.size());
    pwriteAll(files_->hierarchyFd(), loc, sizeof loc, patchAt + kEntryOffsetField,
              files_->hierarchyPath());
  }
  ++report_.chunks;
}

PotreeExportReport Exporter::run(const fs::path& outDir, const std::string& name) {
  const unsigned threads =
      options_.threads ? options_.threads : std::max(1u, std::thread::hardware_concurrency());
  arena_ = std::make_unique<tbb::task_arena>(static_cast<int>(threads));
  progress_ = std::make_unique<Progress>(options_.progress);
  // An older dataset there must stop looking complete before its files change.
  fs::remove(outDir / "metadata.json");
  files_ = std::make_unique<OutputFiles>(outDir);

  progress_->begin("potree", meta_.points, "points");
  std::deque<std::pair<NodeKey, uint64_t>> queue;
  queue.emplace_back(NodeKey::root(), std::numeric_limits<uint64_t>::max());
  while (!queue.empty()) {
    auto [root, patchAt] = queue.front();
    queue.pop_front();
    writeChunk(root, patchAt, queue);
  }
  progress_->end();
  files_->commit(outDir);
  report_.octreeBytes = octreeEnd_;
  report_.hierarchyBytes = hierarchyEnd_;

  // metadata.json, last.
  using ojson = nlohmann::ordered_json;
  const Vec3d s = meta_.scale;
  auto rangeOf = [&](size_t first, size_t n, bool position) {
    ojson mn = ojson::array(), mx = ojson::array();
    for (size_t k = first; k < first + n; ++k) {
      double lo = range_.min[k], hi = range_.max[k];
      if (!(lo <= hi)) lo = hi = 0;  // no points
      if (position) lo = meta_.world(int(k), lo), hi = meta_.world(int(k), hi);
      mn.push_back(lo);
      mx.push_back(hi);
    }
    return std::pair{mn, mx};
  };
  ojson attributes = ojson::array();
  {
    auto [mn, mx] = rangeOf(0, 3, true);
    attributes.push_back({{"name", "position"},
                          {"description", ""},
                          {"size", 12},
                          {"numElements", 3},
                          {"elementSize", 4},
                          {"type", "int32"},
                          {"min", mn},
                          {"max", mx}});
  }
  size_t el = 3;
  for (const auto& a : attrs_) {
    auto [mn, mx] = rangeOf(el, a.elements, false);
    el += a.elements;
    attributes.push_back({{"name", a.name},
                          {"description", a.description},
                          {"size", a.size()},
                          {"numElements", a.elements},
                          {"elementSize", scalarSize(a.type)},
                          {"type", scalarName(a.type)},
                          {"min", mn},
                          {"max", mx}});
  }
  const double cube = meta_.cubeWorldSize();
  std::string projection;
  if (meta_.crs.is_object() && meta_.crs.contains("wkt") && meta_.crs["wkt"].is_string())
    projection = meta_.crs["wkt"].get<std::string>();
  ojson j;
  j["version"] = "2.0";
  j["name"] = name;
  j["description"] = "exported by nestlight from a nestlight octree";
  j["points"] = report_.points;
  j["projection"] = projection;
  j["hierarchy"] = {
      {"firstChunkSize", firstChunkSize_}, {"stepSize", options_.stepSize}, {"depth", meta_.depth}};
  j["offset"] = {meta_.offset.x, meta_.offset.y, meta_.offset.z};
  j["scale"] = {s.x, s.y, s.z};
  j["spacing"] = meta_.spacing > 0 ? meta_.spacing : cube / 128;
  // The octree's cube: the viewer derives every node's box from it by halving.
  j["boundingBox"] = {{"min", {meta_.offset.x, meta_.offset.y, meta_.offset.z}},
                      {"max",
                       {meta_.world(0, meta_.cubeSize), meta_.world(1, meta_.cubeSize),
                        meta_.world(2, meta_.cubeSize)}}};
  j["encoding"] = "DEFAULT";
  j["attributes"] = attributes;
  const std::string text = j.dump(2) + "\n";
  writeFileAtomic(outDir / "metadata.json", text.data(), text.size());
  return report_;
}

}  // namespace

PotreeExportReport exportPotree(const fs::path& octreeDir, const fs::path& outDir,
                                const PotreeExportOptions& options) {
  if (options.stepSize < 1 || options.stepSize > 16)
    throw Error("hierarchy step size must be 1..16, not " + std::to_string(options.stepSize));
  std::error_code ec;
  if (fs::exists(outDir, ec)) {
    if (!fs::is_directory(outDir, ec))
      throw Error(outDir.string(), "", "exists and is not a directory");
    if (fs::exists(octreeDir, ec) && fs::equivalent(outDir, octreeDir, ec))
      throw Error(outDir.string(), "",
                  "is the octree being exported; choose another output directory");
    if (!fs::is_empty(outDir, ec) && !options.overwrite)
      throw Error(outDir.string(), "",
                  "is not empty; pass --force to write the Potree files into it");
  }
  // Opened before the output directory is created: a bad octree leaves nothing behind.
  Exporter exporter(octreeDir, options);
  // Written beside the output and swapped in when complete: a failed export (a full disk) over
  // an existing dataset leaves that dataset as it was. Other files of the folder are kept.
  StagedDirectory staged(outDir, [](const std::string& n) {
    return n == "metadata.json" || n == "hierarchy.bin" || n == "octree.bin" || n == "log.txt" ||
           (n.size() > 4 && n.compare(n.size() - 4, 4, ".tmp") == 0);
  });
  std::string name = options.name;
  if (name.empty()) {
    fs::path p = fs::absolute(octreeDir).lexically_normal();
    if (!p.has_filename()) p = p.parent_path();
    name = p.filename().string();
    if (name.empty()) name = "nestlight";
  }
  PotreeExportReport report = exporter.run(staged.path(), name);
  staged.commit();
  return report;
}

}  // namespace nestlight
