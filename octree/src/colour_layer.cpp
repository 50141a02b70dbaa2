#include "nestlight/octree/colour_layer.h"

#include <Imath/half.h>
#include <fcntl.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

#include "file_io.h"
#include "nestlight/octree/checksum.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/octree_writer.h"

namespace nestlight {

namespace fs = std::filesystem;

namespace {

constexpr int kColourZstdLevel = 3;

void put32(uint8_t* p, uint32_t v) {
  std::memcpy(p, &v, 4);
}
void put64(uint8_t* p, uint64_t v) {
  std::memcpy(p, &v, 8);
}
uint32_t get32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
uint64_t get64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

Metadata readMetadataFile(const fs::path& dir) {
  const fs::path mp = dir / "metadata.json";
  std::ifstream in(mp);
  if (!in) throw Error(mp.string(), "", "cannot open: not an octree folder");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(mp.string(), Error::atByte(e.byte), "invalid JSON");
  }
  return Metadata::fromJson(j, mp.string());
}

bool isLayerFileName(const std::string& n) {
  auto ends = [&](std::string_view s) {
    return n.size() >= s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0;
  };
  // HDR expansion's scratch file (expand.h) is per-point working state of an unfinished run.
  return ends(".layer") || ends(".layer.tmp") || ends(".expand.scratch");
}

}  // namespace

std::vector<uint8_t> encodeColourPayload(const float* rgb, size_t points, double scale,
                                         uint64_t& clamped) {
  // Channel-planar, then all high bytes before all low bytes: neighbouring points have similar
  // colours, so the high bytes repeat and zstd finds them.
  const size_t n = points * 3;
  std::vector<uint8_t> raw(n * 2);
  const double inv = 1.0 / scale;
  for (size_t c = 0; c < 3; ++c)
    for (size_t i = 0; i < points; ++i) {
      const double v = double(rgb[i * 3 + c]) * inv;
      float s = float(v);
      if (!(v >= 0) || !std::isfinite(v)) {
        s = 0, clamped++;
      } else if (v > kHalfMax) {
        s = kHalfMax, clamped++;
      }
      const uint16_t bits = Imath::half(s).bits();
      const size_t k = c * points + i;
      raw[k] = uint8_t(bits >> 8);
      raw[n + k] = uint8_t(bits & 0xff);
    }
  std::vector<uint8_t> out(ZSTD_compressBound(raw.size()));
  const size_t z = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), kColourZstdLevel);
  NL_CHECK_MSG(!ZSTD_isError(z), ZSTD_getErrorName(z));
  out.resize(z);
  return out;
}

std::string decodeColourPayload(const uint8_t* data, size_t size, size_t points, double scale,
                                std::vector<float>& rgb) {
  rgb.clear();
  if (points > (size_t(1) << 32)) return "point count beyond 2^32";
  const size_t n = points * 3, rawSize = n * 2;
  if (points == 0)
    return size == 0 || ZSTD_getFrameContentSize(data, size) == 0
               ? ""
               : "payload of an empty node holds data";
  const unsigned long long frame = ZSTD_getFrameContentSize(data, size);
  if (frame == ZSTD_CONTENTSIZE_ERROR || frame == ZSTD_CONTENTSIZE_UNKNOWN)
    return "not a zstd frame with a known size";
  if (frame != rawSize)
    return "holds " + std::to_string(frame / 6) + " colours where the node has " +
           std::to_string(points);
  std::vector<uint8_t> raw(rawSize);
  const size_t got = ZSTD_decompress(raw.data(), rawSize, data, size);
  if (ZSTD_isError(got) || got != rawSize) return "zstd frame does not decompress";
  rgb.resize(n);
  for (size_t c = 0; c < 3; ++c)
    for (size_t i = 0; i < points; ++i) {
      const size_t k = c * points + i;
      Imath::half h;
      h.setBits(uint16_t(raw[k] << 8 | raw[n + k]));
      rgb[i * 3 + c] = float(double(float(h)) * scale);
    }
  return {};
}

std::string parseLayerIndex(const uint8_t* data, size_t size, std::vector<LayerIndexEntry>& out) {
  out.clear();
  if (size % kLayerIndexEntryBytes != 0)
    return "index of " + std::to_string(size) + " bytes is not a whole number of 40-byte entries";
  const size_t count = size / kLayerIndexEntryBytes;
  out.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    const uint8_t* p = data + i * kLayerIndexEntryBytes;
    LayerIndexEntry e;
    e.key.level = get32(p);
    e.key.x = get32(p + 4), e.key.y = get32(p + 8), e.key.z = get32(p + 12);
    e.points = get32(p + 16);
    e.byteSize = get32(p + 20);
    e.byteOffset = get64(p + 24);
    e.checksum = get64(p + 32);
    if (e.key.level > 30)
      return "entry " + std::to_string(i) + ": level " + std::to_string(e.key.level) + " beyond 30";
    const uint32_t side = 1u << e.key.level;
    if (e.key.x >= side || e.key.y >= side || e.key.z >= side)
      return "entry " + std::to_string(i) + ": key outside its level";
    if (i > 0 && !(out.back().key < e.key))
      return "entry " + std::to_string(i) + ": keys not in increasing order";
    out.push_back(e);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------

void checkLayerName(const std::string& name) {
  if (name.empty() || name.find_first_of("/.") != std::string::npos)
    throw Error("layer name '" + name + "': must be non-empty, without '/' or '.'");
  if (name == "rgb")
    throw Error(
        "layer name 'rgb': scene files read \"colour\": \"rgb\" as the scan's recorded colour, so "
        "a "
        "layer of that name could never be chosen; use another name (the default is 'hdr')");
}

ColourLayerWriter::ColourLayerWriter(fs::path dir, std::string name, double scale)
    : dir_(std::move(dir)), name_(std::move(name)), scale_(scale) {
  NL_CHECK(scale_ > 0 && std::isfinite(scale_));
  checkLayerName(name_);
  if (!fs::exists(dir_ / "metadata.json"))
    throw Error((dir_ / "metadata.json").string(), "", "not an octree folder (no metadata.json)");
  // A name no earlier version used: the current layer stays readable until metadata.json names
  // the new one.
  std::random_device rd;
  const uint64_t token = (uint64_t(rd()) << 32 ^ rd()) ^
                         uint64_t(std::chrono::steady_clock::now().time_since_epoch().count());
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(token));
  tmp_ = dir_ / (name_ + "." + hex + ".layer.tmp");
  fd_ = ::open(tmp_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw Error(tmp_.string(), "", std::string("cannot create: ") + std::strerror(errno));
}

ColourLayerWriter::~ColourLayerWriter() {
  if (fd_ >= 0) ::close(fd_);
  if (!finished_) {
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void ColourLayerWriter::writeNode(const NodeKey& key, const float* rgb, size_t points) {
  NL_CHECK_MSG(points < (uint64_t(1) << 32), "node " + key.name() + " holds 2^32 points or more");
  uint64_t clamped = 0;
  std::vector<uint8_t> bytes;
  if (points > 0) bytes = encodeColourPayload(rgb, points, scale_, clamped);
  clamped_ += clamped;
  LayerIndexEntry e;
  e.key = key;
  e.points = uint32_t(points);
  e.byteSize = uint32_t(bytes.size());
  e.checksum = checksum64(bytes.data(), bytes.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    e.byteOffset = offset_;
    offset_ += bytes.size();
    entries_.push_back(e);
  }
  detail::pwriteAll(fd_, bytes.data(), bytes.size(), e.byteOffset, tmp_.string());
}

LayerRecord ColourLayerWriter::finish(const nlohmann::json& build) {
  NL_CHECK(!finished_);
  std::sort(entries_.begin(), entries_.end(), [](auto& a, auto& b) { return a.key < b.key; });
  for (size_t i = 1; i < entries_.size(); ++i)
    if (entries_[i].key == entries_[i - 1].key)
      throw Error(tmp_.string(), "", "node " + entries_[i].key.name() + " written twice");
  // Every node of the octree, with its point count: a layer with holes would be read as whole.
  uint64_t points = 0;
  {
    OctreeReader reader(dir_);
    auto nodes = reader.allNodes();
    std::sort(nodes.begin(), nodes.end(), [](auto& a, auto& b) { return a.first < b.first; });
    size_t j = 0;
    for (const auto& [key, e] : nodes) {
      if (j >= entries_.size() || !(entries_[j].key == key))
        throw Error(
            tmp_.string(), "",
            "node " + key.name() + " of the octree has no colours in layer '" + name_ + "'");
      if (entries_[j].points != e.numPoints)
        throw Error(tmp_.string(), "",
                    "node " + key.name() + ": " + std::to_string(entries_[j].points) +
                        " colours for " + std::to_string(e.numPoints) + " points");
      points += e.numPoints;
      ++j;
    }
    if (j != entries_.size())
      throw Error(tmp_.string(), "", "node " + entries_[j].key.name() + " is not in the octree");
  }
  std::vector<uint8_t> index(entries_.size() * kLayerIndexEntryBytes);
  for (size_t i = 0; i < entries_.size(); ++i) {
    uint8_t* p = index.data() + i * kLayerIndexEntryBytes;
    const auto& e = entries_[i];
    put32(p, e.key.level), put32(p + 4, e.key.x), put32(p + 8, e.key.y), put32(p + 12, e.key.z);
    put32(p + 16, e.points), put32(p + 20, e.byteSize);
    put64(p + 24, e.byteOffset), put64(p + 32, e.checksum);
  }
  detail::pwriteAll(fd_, index.data(), index.size(), offset_, tmp_.string());
  if (::fsync(fd_) != 0)
    throw Error(tmp_.string(), "", std::string("fsync failed: ") + std::strerror(errno));
  ::close(fd_);
  fd_ = -1;

  LayerRecord r;
  r.name = name_;
  r.kind = "colour";
  r.encoding = "half_rgb_zstd";
  fs::path final = tmp_;
  final.replace_extension();  // drops ".tmp"
  r.file = final.filename().string();
  r.indexOffset = offset_;
  r.indexBytes = index.size();
  r.indexChecksum = checksum64(index.data(), index.size());
  r.bytes = offset_ + index.size();
  r.nodes = entries_.size();
  r.points = points;
  r.scale = scale_;
  r.build = build;
  fs::rename(tmp_, final);

  // The switch: metadata.json names the new file (or, killed before, still the old one).
  Metadata meta = readMetadataFile(dir_);
  std::string previous;
  auto it = std::find_if(meta.layers.begin(), meta.layers.end(),
                         [&](auto& l) { return l.name == name_; });
  if (it != meta.layers.end()) {
    previous = it->file;
    *it = r;
  } else {
    meta.layers.push_back(r);
  }
  const std::string text = meta.toJson().dump(2) + "\n";
  writeFileAtomic(dir_ / "metadata.json", text.data(), text.size());
  finished_ = true;
  if (!previous.empty() && previous != r.file) {
    std::error_code ec;
    fs::remove(dir_ / previous, ec);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------

ColourLayerReader::ColourLayerReader(const fs::path& dir, const Metadata& meta,
                                     std::string_view name) {
  const LayerRecord* r = meta.layer(name);
  if (!r)
    throw Error((dir / "metadata.json").string(), "",
                "the octree has no layer '" + std::string(name) +
                    "' (run `nestlight expand-hdr` to make the hdr layer)");
  record_ = *r;
  path_ = dir / r->file;
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw Error(path_.string(), "", std::string("cannot open: ") + std::strerror(errno));
  try {
    const auto size = fs::file_size(path_);
    if (size != r->bytes)
      throw Error(path_.string(), "",
                  "holds " + std::to_string(size) + " bytes where metadata.json records " +
                      std::to_string(r->bytes));
    if (r->indexBytes > (uint64_t(1) << 34))
      throw Error(path_.string(), "", "index larger than 16 GiB");
    std::vector<uint8_t> index(r->indexBytes);
    detail::preadAll(fd_, index.data(), index.size(), r->indexOffset, path_.string());
    if (checksum64(index.data(), index.size()) != r->indexChecksum)
      throw Error(path_.string(), Error::atByte(r->indexOffset), "index checksum mismatch");
    std::string why = parseLayerIndex(index.data(), index.size(), entries_);
    if (!why.empty()) throw Error(path_.string(), Error::atByte(r->indexOffset), why);
    for (size_t i = 0; i < entries_.size(); ++i) {
      const auto& e = entries_[i];
      if (e.byteOffset + e.byteSize > r->indexOffset)
        throw Error(path_.string(), Error::atByte(r->indexOffset + i * kLayerIndexEntryBytes),
                    "node " + e.key.name() + "'s payload lies beyond the payload area");
      byKey_[e.key] = i;
    }
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

ColourLayerReader::~ColourLayerReader() {
  if (fd_ >= 0) ::close(fd_);
}

const LayerIndexEntry* ColourLayerReader::find(const NodeKey& key) const {
  auto it = byKey_.find(key);
  return it == byKey_.end() ? nullptr : &entries_[it->second];
}

std::vector<float> ColourLayerReader::readNode(const NodeKey& key, uint32_t expectedPoints) const {
  const LayerIndexEntry* e = find(key);
  if (!e) throw Error(path_.string(), "", "no colours for node " + key.name());
  if (e->points != expectedPoints)
    throw Error(path_.string(), Error::atByte(e->byteOffset),
                "node " + key.name() + " has " + std::to_string(e->points) + " colours for " +
                    std::to_string(expectedPoints) + " points");
  std::vector<uint8_t> bytes(e->byteSize);
  detail::preadAll(fd_, bytes.data(), bytes.size(), e->byteOffset, path_.string());
  if (checksum64(bytes.data(), bytes.size()) != e->checksum)
    throw Error(path_.string(), Error::atByte(e->byteOffset),
                "node " + key.name() + ": checksum mismatch");
  std::vector<float> rgb;
  const std::string why =
      decodeColourPayload(bytes.data(), bytes.size(), e->points, record_.scale, rgb);
  if (!why.empty())
    throw Error(path_.string(), Error::atByte(e->byteOffset), "node " + key.name() + ": " + why);
  return rgb;
}

std::vector<std::string> orphanLayerFiles(const fs::path& dir, const Metadata& meta) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string n = entry.path().filename().string();
    if (!isLayerFileName(n)) continue;
    bool named = false;
    for (const auto& l : meta.layers) named = named || l.file == n;
    if (!named) out.push_back(n);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> removeOrphanLayerFiles(const fs::path& dir, const Metadata& meta) {
  auto out = orphanLayerFiles(dir, meta);
  for (const auto& n : out) {
    std::error_code ec;
    fs::remove(dir / n, ec);
  }
  return out;
}

}  // namespace nestlight
