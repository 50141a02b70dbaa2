// The compressed point data of one LAZ file: its chunk table, and the decoding of chunks into
// LAS point records on all cores. Private to converters/src; the LAS reader owns one when the
// point format byte says the points are compressed.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "laz/format.h"
#include "nestlight/converters/byte_source.h"

namespace nestlight::laz {

// Decoded records. Not zero-filled: a chunk that claims more points than its bytes hold runs dry
// after writing a few pages, and untouched pages of a large claim cost no memory.
struct RecordBuffer {
  std::unique_ptr<uint8_t[]> bytes;
  size_t size = 0, capacity = 0;
  uint8_t* data() { return bytes.get(); }
  const uint8_t* data() const { return bytes.get(); }
  void resize(size_t n) {
    if (n > capacity) {
      bytes.reset(new uint8_t[n]);
      capacity = n;
    }
    size = n;
  }
  void release() {
    bytes.reset();
    size = capacity = 0;
  }
};

struct Chunk {
  uint64_t offset = 0;      // first byte in the file
  uint64_t bytes = 0;       // 0 while unknown (files without a chunk table)
  uint64_t firstPoint = 0;  // index of its first point in the file
  uint32_t points = 0;
};

class LazPoints {
 public:
  // `pointStart` is the header's offset to point data, `dataEnd` where the point data must end
  // (the first EVLR, else the end of the file). Throws nestlight::Error naming the file, the
  // chunk and the byte offset; with `lenient`, damage that leaves intact chunks becomes warnings.
  // `hierarchyChunks`: the chunks a COPC hierarchy lists (empty otherwise), cross-checked with
  // the chunk table and used in its place when the table is missing or damaged.
  LazPoints(std::shared_ptr<ByteSource> src, LaszipInfo info, uint64_t pointStart, uint64_t dataEnd,
            uint64_t declaredPoints, bool lenient, std::function<void(std::string)> warn,
            std::vector<Chunk> hierarchyChunks = {});
  ~LazPoints();

  const LaszipInfo& info() const { return info_; }
  size_t recordSize() const { return recordSize_; }
  // Points the chunks hold (after reconciling the header with the chunk table).
  uint64_t points() const { return points_; }
  const std::vector<Chunk>& chunks() const { return chunks_; }
  bool hasChunkTable() const { return tabled_; }
  // "chunk table", "COPC hierarchy" or "sequential" (no table: found while decoding).
  const char* chunkSource() const { return source_; }

  // Decodes the chunks `which` (ascending) into `out` (their points' records back to back, in
  // order), on all cores when `parallel`. Returns the number of points written; a damaged chunk
  // throws, or with `lenient` is skipped, warned about and its points added to unreadable().
  // Without a chunk table, chunks are found as they are decoded: `which` must be the last one
  // known, and calls must not overlap. With a table, calls may run concurrently.
  uint64_t decode(const std::vector<size_t>& which, RecordBuffer& out, bool parallel = true);
  // Points the file declares that could not be decoded: chunks lost at open (lenient) and
  // damaged chunks met since the last rewind().
  uint64_t unreadable() const { return unreadable_.load(); }
  void rewind() { unreadable_ = unreadableAtOpen_; }

 private:
  void readChunkTable(uint64_t declaredPoints);
  void checkHierarchy();
  void countLastChunk(uint64_t declaredPoints);
  void useHierarchy(uint64_t declaredPoints);
  [[noreturn]] void fail(uint64_t at, const std::string& reason) const;
  std::string chunkName(size_t i) const;

  std::shared_ptr<ByteSource> src_;
  LaszipInfo info_;
  size_t recordSize_;
  uint64_t pointStart_, dataEnd_;
  bool lenient_;
  std::function<void(std::string)> warn_;
  bool tabled_ = false;
  const char* source_ = "chunk table";
  std::vector<Chunk> hierarchy_;
  std::vector<Chunk> chunks_;
  uint64_t points_ = 0;
  std::atomic<uint64_t> unreadable_{0};
  uint64_t unreadableAtOpen_ = 0;
  uint64_t declaredShort_ = 0;  // points the chunks hold beyond the header's count
  std::mutex warnMutex_;        // warn_ from concurrent decodes
  uint64_t tableStart_ = 0;
  struct Decoders;  // one ChunkDecoder per thread
  std::unique_ptr<Decoders> decoders_;
};

}  // namespace nestlight::laz
