#include "nestlight/octree/octree_reader.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>

#include "file_io.h"
#include "nestlight/octree/checksum.h"
#include "nestlight/octree/codec.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace fs = std::filesystem;

namespace {
// Per thread, over all readers: what threadReadCalls() and threadBytesRead() report.
thread_local uint64_t tlsReadCalls = 0;
thread_local uint64_t tlsBytesRead = 0;

void readAll(int fd, void* dst, size_t size, uint64_t offset, const std::string& path) {
  tlsBytesRead += size;
  detail::preadAll(fd, dst, size, offset, path);
}

// Proxies are counted as entries too until their chunk is loaded: at most 512 per chunk.
size_t kMaxProxyOverhead(uint64_t nodes) {
  return static_cast<size_t>(nodes) + 1024;
}

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
    std::unique_lock<std::mutex> lock(mutex_);
    loadChunk(lock, NodeKey::root(), 0, meta_.rootChunkSize, meta_.rootChunkChecksum);
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

uint64_t OctreeReader::threadReadCalls() {
  return tlsReadCalls;
}
uint64_t OctreeReader::threadBytesRead() {
  return tlsBytesRead;
}

// Called and returns with `lock` held; reads the file without it, so that peek() and readers of
// other chunks never wait on this read. A failure is remembered and rethrown for the same chunk.
void OctreeReader::loadChunk(std::unique_lock<std::mutex>& lock, const NodeKey& root,
                             uint64_t offset, uint64_t size, uint64_t checksum) {
  const std::string path = (dir_ / meta_.hierarchyFile).string();
  auto fail = [&](const Error& e) {
    failedChunks_.emplace(offset, e);
    throw e;
  };
  if (size > 1 << 20 || size > meta_.hierarchyBytes || offset > meta_.hierarchyBytes - size)
    fail(Error(path, Error::atByte(offset),
               "hierarchy chunk of node " + root.name() + " out of range"));
  // Each chunk is read once: a damaged file whose proxies point back at loaded chunks would
  // otherwise expand without end.
  if (!loadedChunks_.insert(offset).second)
    fail(Error(path, Error::atByte(offset),
               "hierarchy chunk of node " + root.name() + " is referenced twice"));
  readingChunks_.insert(offset);
  lock.unlock();
  std::vector<std::pair<NodeKey, HierarchyEntry>> entries;
  std::optional<Error> error;
  try {
    std::vector<uint8_t> bytes(size);
    readAll(hierarchyFd_, bytes.data(), size, offset, path);
    hierarchyBytesRead_ += size;
    if (checksum64(bytes.data(), bytes.size()) != checksum)
      throw Error(path, Error::atByte(offset),
                  "checksum mismatch in the hierarchy chunk of node " + root.name());
    std::string err =
        parseHierarchyChunk(bytes.data(), bytes.size(), root, meta_.hierarchyStep, entries);
    if (!err.empty()) throw Error(path, Error::atByte(offset), err);
  } catch (const Error& e) {
    error = e;
  }
  lock.lock();
  readingChunks_.erase(offset);
  chunkRead_.notify_all();
  if (error) fail(*error);
  if (entries_.size() + entries.size() > meta_.nodes + kMaxProxyOverhead(meta_.nodes))
    fail(Error(path, Error::atByte(offset),
               "hierarchy holds more nodes than metadata's " + std::to_string(meta_.nodes)));
  for (auto& [k, e] : entries) {
    auto it = entries_.find(k);
    // The chunk's own root entry replaces the proxy that pointed here.
    if (it == entries_.end() || it->second.type == NodeType::Proxy) entries_[k] = e;
  }
  if (entries_.at(root).type == NodeType::Proxy)
    fail(Error(path, Error::atByte(offset), "chunk root " + root.name() + " is itself a proxy"));
}

std::optional<HierarchyEntry> OctreeReader::resolve(const NodeKey& key) {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    // The first proxy on the path from the root: its chunk is the next to read.
    const HierarchyEntry* proxy = nullptr;
    NodeKey at;
    for (uint32_t l = 0; l <= key.level && !proxy; ++l) {
      at = key.ancestor(l);
      auto it = entries_.find(at);
      if (it == entries_.end()) return std::nullopt;
      if (it->second.type == NodeType::Proxy) proxy = &it->second;
    }
    if (!proxy) return entries_.at(key);
    const HierarchyEntry p = *proxy;
    if (auto f = failedChunks_.find(p.byteOffset); f != failedChunks_.end()) throw f->second;
    if (readingChunks_.count(p.byteOffset)) {
      chunkRead_.wait(lock);
      continue;
    }
    loadChunk(lock, at, p.byteOffset, p.byteSize, p.checksum);
  }
}

std::optional<HierarchyEntry> OctreeReader::node(const NodeKey& key) {
  ++tlsReadCalls;
  return resolve(key);
}

std::optional<HierarchyEntry> OctreeReader::ensureLoaded(const NodeKey& key) {
  ++tlsReadCalls;
  return resolve(key);
}

std::optional<HierarchyEntry> OctreeReader::peek(const NodeKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = entries_.find(key);
  if (it == entries_.end()) return std::nullopt;
  return it->second;
}

bool OctreeReader::hierarchyPending(const NodeKey& key) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (uint32_t l = 0; l <= key.level; ++l) {
    auto it = entries_.find(key.ancestor(l));
    if (it == entries_.end()) return false;
    if (it->second.type == NodeType::Proxy) return true;
  }
  return false;
}

std::vector<NodeKey> OctreeReader::children(const NodeKey& key) {
  ++tlsReadCalls;
  std::vector<NodeKey> out;
  auto e = resolve(key);
  if (!e) return out;
  for (int i = 0; i < 8; ++i)
    if (e->childMask & (1u << i)) out.push_back(key.child(i));
  return out;
}

std::vector<std::pair<NodeKey, HierarchyEntry>> OctreeReader::allNodes() {
  ++tlsReadCalls;
  std::vector<std::pair<NodeKey, HierarchyEntry>> out;
  std::deque<NodeKey> queue{NodeKey::root()};
  while (!queue.empty()) {
    NodeKey k = queue.front();
    queue.pop_front();
    auto e = resolve(k);
    if (!e) continue;
    out.emplace_back(k, *e);
    for (int i = 0; i < 8; ++i)
      if (e->childMask & (1u << i)) queue.push_back(k.child(i));
  }
  return out;
}

std::vector<uint8_t> OctreeReader::readPayload(const HierarchyEntry& e) {
  ++tlsReadCalls;
  const std::string path = (dir_ / meta_.payloadFile).string();
  if (e.byteSize > meta_.payloadBytes || e.byteOffset > meta_.payloadBytes - e.byteSize ||
      e.byteSize > (uint64_t(1) << 32))
    throw Error(path, Error::atByte(e.byteOffset), "payload range lies outside the file");
  std::vector<uint8_t> bytes(e.byteSize);
  readAll(payloadFd_, bytes.data(), bytes.size(), e.byteOffset, path);
  payloadBytesRead_ += bytes.size();
  return bytes;
}

PointBuffer OctreeReader::readNode(const NodeKey& key) {
  ++tlsReadCalls;
  auto e = resolve(key);
  if (!e) throw Error(dir_.string(), "node " + key.name(), "no such node");
  const std::string path = (dir_ / meta_.payloadFile).string();
  if (e->numPoints > meta_.points)
    throw Error(path, "node " + key.name(), "claims more points than the whole octree holds");
  std::vector<uint8_t> bytes = readPayload(*e);
  if (checksum64(bytes.data(), bytes.size()) != e->checksum)
    throw Error(path, Error::atByte(e->byteOffset), "checksum mismatch in node " + key.name());
  PointBuffer pts(meta_.layout.stride());
  std::string err =
      decodePayload(e->codec, meta_.layout, bytes.data(), bytes.size(), e->numPoints, pts);
  if (!err.empty())
    throw Error(path, Error::atByte(e->byteOffset), "node " + key.name() + ": " + err);
  const uint32_t size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * size, key.y * size, key.z * size};
  for (size_t i = 0; i < pts.pos.size(); ++i) pts.pos[i] += base[i % 3];
  return pts;
}

}  // namespace nestlight
