#include "nestlight/octree/octree_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <unordered_set>

#include "file_io.h"
#include "nestlight/octree/checksum.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace fs = std::filesystem;

bool isOctreeFileName(const std::string& n) {
  auto ends = [&](std::string_view s) {
    return n.size() >= s.size() && n.compare(n.size() - s.size(), s.size(), s) == 0;
  };
  return n == "metadata.json" || n == "hierarchy.bin" || n == "octree.bin" || ends(".tmp") ||
         ends(".layer") || ends(".expand.scratch") || n.rfind(".build-", 0) == 0;
}

void writeFileAtomic(const fs::path& path, const void* bytes, size_t size) {
  fs::path tmp = path;
  tmp += ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(tmp.string(), "", std::string("cannot create: ") + std::strerror(errno));
  try {
    detail::pwriteAll(fd, bytes, size, 0, tmp.string());
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::fsync(fd);
  ::close(fd);
  fs::rename(tmp, path);
}

OctreeWriter::OctreeWriter(fs::path dir, PointLayout layout, Codec codec, bool overwrite)
    : dir_(std::move(dir)), layout_(std::move(layout)), codec_(codec) {
  if (fs::exists(dir_ / "metadata.json") && !overwrite)
    throw Error(dir_.string(), "", "already holds an octree; pass --overwrite to replace it");
  fs::create_directories(dir_);
  // An old octree must stop looking complete before any of its files change.
  fs::remove(dir_ / "metadata.json");
  fs::path tmp = dir_ / "octree.bin.tmp";
  fd_ = ::open(tmp.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error(tmp.string(), "", std::string("cannot create: ") + std::strerror(errno));
}

OctreeWriter::~OctreeWriter() {
  if (fd_ >= 0) ::close(fd_);
  if (!finished_) {
    std::error_code ec;
    fs::remove(dir_ / "octree.bin.tmp", ec);
  }
}

void OctreeWriter::writeNode(const NodeKey& key, const PointBuffer& points, uint8_t spacingCode) {
  NL_CHECK(points.stride == layout_.stride());
  NL_CHECK_MSG(points.size() < (uint64_t(1) << 32),
               "node " + key.name() + " holds 2^32 points or more");
  // An empty node (its points all moved up into its parent) has an empty payload in any codec.
  std::vector<uint8_t> bytes;
  if (!points.empty()) bytes = encodePayload(codec_, layout_, points);
  NodeRecord r;
  r.key = key;
  r.codec = codec_;
  r.spacingCode = spacingCode;
  r.numPoints = static_cast<uint32_t>(points.size());
  r.byteSize = bytes.size();
  r.checksum = checksum64(bytes.data(), bytes.size());
  {
    std::lock_guard<std::mutex> lock(mutex_);
    r.byteOffset = offset_;
    offset_ += bytes.size();
    nodes_.push_back(r);
  }
  // Offsets are reserved under the lock; the write itself runs in parallel.
  detail::pwriteAll(fd_, bytes.data(), bytes.size(), r.byteOffset,
                    (dir_ / "octree.bin.tmp").string());
}

namespace {

// Sampling can move every point of a sparse leaf up into its parent; such a node stays only if it
// has children. The root always stays.
std::vector<NodeRecord> pruneEmptyLeaves(std::vector<NodeRecord> nodes) {
  std::vector<NodeRecord> kept;
  kept.reserve(nodes.size());
  std::sort(nodes.begin(), nodes.end(), [](const NodeRecord& a, const NodeRecord& b) {
    return b.key < a.key;
  });  // deepest first
  std::unordered_set<NodeKey, NodeKeyHash> keptKeys;
  for (const auto& n : nodes) {
    bool hasChild = false;
    for (int i = 0; i < 8 && !hasChild; ++i) hasChild = keptKeys.count(n.key.child(i)) > 0;
    if (n.numPoints == 0 && !hasChild && n.key.level > 0) continue;
    keptKeys.insert(n.key);
    kept.push_back(n);
  }
  std::reverse(kept.begin(), kept.end());
  return kept;
}

// The payload (dir/octree.bin.tmp, synced and closed) renamed into place, then the hierarchy and
// the metadata, each written atomically: metadata.json, last, makes the octree complete.
void writeHierarchyAndMetadata(const fs::path& dir, Metadata& meta, std::vector<NodeRecord> nodes,
                               uint64_t payloadBytes) {
  nodes = pruneEmptyLeaves(std::move(nodes));
  meta.depth = 0;
  for (const auto& n : nodes) meta.depth = std::max(meta.depth, n.key.level);
  HierarchyBlob h = buildHierarchy(nodes, meta.hierarchyStep);
  meta.payloadBytes = payloadBytes;
  meta.nodes = nodes.size();
  meta.hierarchyBytes = h.bytes.size();
  meta.rootChunkSize = h.rootChunkSize;
  meta.rootChunkChecksum = h.rootChunkChecksum;
  fs::rename(dir / "octree.bin.tmp", dir / meta.payloadFile);
  writeFileAtomic(dir / meta.hierarchyFile, h.bytes.data(), h.bytes.size());
  std::string text = meta.toJson().dump(2) + "\n";
  writeFileAtomic(dir / "metadata.json", text.data(), text.size());
}

}  // namespace

void OctreeWriter::finish(Metadata& meta) {
  writeHierarchyAndMetadata(dir_, meta, finishPart(), offset_);
}

std::vector<NodeRecord> OctreeWriter::finishPart() {
  NL_CHECK(!finished_);
  if (::fsync(fd_) != 0)
    throw Error((dir_ / "octree.bin.tmp").string(), "",
                std::string("fsync failed: ") + std::strerror(errno));
  ::close(fd_);
  fd_ = -1;
  finished_ = true;  // the payload stays: renamed into place, or a part copied into the output
  return std::move(nodes_);
}

void OctreeWriter::finishAssembled(const fs::path& dir, Metadata& meta,
                                   std::vector<NodeRecord> nodes, uint64_t payloadBytes) {
  writeHierarchyAndMetadata(dir, meta, std::move(nodes), payloadBytes);
}

}  // namespace nestlight
