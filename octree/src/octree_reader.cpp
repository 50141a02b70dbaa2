#include "nestlight/octree/octree_reader.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>

#include "nestlight/octree/checksum.h"
#include "nestlight/octree/codec.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace fs = std::filesystem;

namespace {
void readAll(int fd, void* dst, size_t size, uint64_t offset, const std::string& path) {
  uint8_t* p = static_cast<uint8_t*>(dst);
  while (size > 0) {
    ssize_t r = ::pread(fd, p, size, static_cast<off_t>(offset));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0)
      throw Error(path, Error::atByte(offset),
                  r == 0 ? "file ends early" : std::string("read failed: ") + std::strerror(errno));
    p += r;
    size -= static_cast<size_t>(r);
    offset += static_cast<uint64_t>(r);
  }
}

// Proxies are counted as entries too until their chunk is loaded: at most 512 per chunk.
size_t kMaxProxyOverhead(uint64_t nodes) { return static_cast<size_t>(nodes) + 1024; }

int openOrThrow(const fs::path& p) {
  int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error(p.string(), "", std::string("cannot open: ") + std::strerror(errno));
  return fd;
}
}  // namespace

OctreeReader::OctreeReader(const fs::path& dir) : dir_(dir) {
  fs::path mp = dir / "metadata.json";
  if (!fs::exists(mp))
    throw Error(mp.string(), "",
                "no metadata.json: not an octree folder, or a conversion that did not finish");
  std::ifstream in(mp);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(mp.string(), Error::atByte(e.byte), "invalid JSON");
  }
  meta_ = Metadata::fromJson(j, mp.string());
  try {
    payloadFd_ = openOrThrow(dir / meta_.payloadFile);
    hierarchyFd_ = openOrThrow(dir / meta_.hierarchyFile);
    if (meta_.rootChunkSize > 64 * 1024)
      throw Error(mp.string(), "field 'hierarchy.root_chunk_size'", "larger than 64 KiB");
    loadChunk(NodeKey::root(), 0, meta_.rootChunkSize, meta_.rootChunkChecksum);
  } catch (...) {
    // The destructor does not run for a half-built object.
    if (payloadFd_ >= 0) ::close(payloadFd_);
    if (hierarchyFd_ >= 0) ::close(hierarchyFd_);
    throw;
  }
}

OctreeReader::~OctreeReader() {
  if (payloadFd_ >= 0) ::close(payloadFd_);
  if (hierarchyFd_ >= 0) ::close(hierarchyFd_);
}

void OctreeReader::loadChunk(const NodeKey& root, uint64_t offset, uint64_t size,
                             uint64_t checksum) {
  const std::string path = (dir_ / meta_.hierarchyFile).string();
  if (size > 1 << 20 || size > meta_.hierarchyBytes || offset > meta_.hierarchyBytes - size)
    throw Error(path, Error::atByte(offset), "hierarchy chunk of node " + root.name() + " out of range");
  // Each chunk is read once: a damaged file whose proxies point back at loaded chunks would
  // otherwise expand without end.
  if (!loadedChunks_.insert(offset).second)
    throw Error(path, Error::atByte(offset), "hierarchy chunk of node " + root.name() + " is referenced twice");
  std::vector<uint8_t> bytes(size);
  readAll(hierarchyFd_, bytes.data(), size, offset, path);
  hierarchyBytesRead_ += size;
  if (checksum64(bytes.data(), bytes.size()) != checksum)
    throw Error(path, Error::atByte(offset), "checksum mismatch in the hierarchy chunk of node " + root.name());
  std::vector<std::pair<NodeKey, HierarchyEntry>> entries;
  std::string err = parseHierarchyChunk(bytes.data(), bytes.size(), root, meta_.hierarchyStep, entries);
  if (!err.empty()) throw Error(path, Error::atByte(offset), err);
  if (entries_.size() + entries.size() > meta_.nodes + kMaxProxyOverhead(meta_.nodes))
    throw Error(path, Error::atByte(offset), "hierarchy holds more nodes than metadata's " + std::to_string(meta_.nodes));
  for (auto& [k, e] : entries) {
    auto it = entries_.find(k);
    // The chunk's own root entry replaces the proxy that pointed here.
    if (it == entries_.end() || it->second.type == NodeType::Proxy) entries_[k] = e;
  }
  if (entries_.at(root).type == NodeType::Proxy)
    throw Error(path, Error::atByte(offset), "chunk root " + root.name() + " is itself a proxy");
}

std::optional<HierarchyEntry> OctreeReader::node(const NodeKey& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Walk down from the deepest loaded ancestor, loading chunks on the way.
  for (uint32_t l = 0; l <= key.level; ++l) {
    NodeKey a = key.ancestor(l);
    auto it = entries_.find(a);
    if (it == entries_.end()) return std::nullopt;
    if (it->second.type == NodeType::Proxy) {
      HierarchyEntry p = it->second;
      loadChunk(a, p.byteOffset, p.byteSize, p.checksum);
    }
  }
  return entries_.at(key);
}

std::vector<NodeKey> OctreeReader::children(const NodeKey& key) {
  std::vector<NodeKey> out;
  auto e = node(key);
  if (!e) return out;
  for (int i = 0; i < 8; ++i)
    if (e->childMask & (1u << i)) out.push_back(key.child(i));
  return out;
}

std::vector<std::pair<NodeKey, HierarchyEntry>> OctreeReader::allNodes() {
  std::vector<std::pair<NodeKey, HierarchyEntry>> out;
  std::deque<NodeKey> queue{NodeKey::root()};
  while (!queue.empty()) {
    NodeKey k = queue.front();
    queue.pop_front();
    auto e = node(k);
    if (!e) continue;
    out.emplace_back(k, *e);
    for (int i = 0; i < 8; ++i)
      if (e->childMask & (1u << i)) queue.push_back(k.child(i));
  }
  return out;
}

std::vector<uint8_t> OctreeReader::readPayload(const HierarchyEntry& e) {
  const std::string path = (dir_ / meta_.payloadFile).string();
  if (e.byteSize > meta_.payloadBytes || e.byteOffset > meta_.payloadBytes - e.byteSize ||
      e.byteSize > (uint64_t(1) << 32))
    throw Error(path, Error::atByte(e.byteOffset), "payload range lies outside the file");
  std::vector<uint8_t> bytes(e.byteSize);
  readAll(payloadFd_, bytes.data(), bytes.size(), e.byteOffset, path);
  return bytes;
}

PointBuffer OctreeReader::readNode(const NodeKey& key) {
  auto e = node(key);
  if (!e) throw Error(dir_.string(), "node " + key.name(), "no such node");
  const std::string path = (dir_ / meta_.payloadFile).string();
  if (e->numPoints > meta_.points)
    throw Error(path, "node " + key.name(), "claims more points than the whole octree holds");
  std::vector<uint8_t> bytes = readPayload(*e);
  if (checksum64(bytes.data(), bytes.size()) != e->checksum)
    throw Error(path, Error::atByte(e->byteOffset), "checksum mismatch in node " + key.name());
  PointBuffer pts(meta_.layout.stride());
  std::string err = decodePayload(e->codec, meta_.layout, bytes.data(), bytes.size(), e->numPoints, pts);
  if (!err.empty()) throw Error(path, Error::atByte(e->byteOffset), "node " + key.name() + ": " + err);
  const uint32_t size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * size, key.y * size, key.z * size};
  for (size_t i = 0; i < pts.pos.size(); ++i) pts.pos[i] += base[i % 3];
  return pts;
}

}  // namespace nestlight
