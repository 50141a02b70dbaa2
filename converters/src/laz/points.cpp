// The chunk table of LAZ files and parallel chunk decoding.
//
// Chunked LAZ (LASzip reference implementation, lasreadpoint.cpp; Isenburg, "LASzip: lossless
// compression of LiDAR data", PE&RS 79(2), 2013): the point data starts with the 64-bit offset of
// the chunk table (-1: it is in the last 8 bytes of the file; the offset of the point data itself:
// the compressor was interrupted and wrote none). The table is a version (0), a chunk count and
// an arithmetic-coded list of each chunk's point count (variable-size chunks only) and byte size,
// each predicted from the previous chunk's. Chunks are independent, so they decode in parallel.
//
// Every number in the table is a claim: chunks must lie inside the point data, their counts must
// add up to the header's, and a chunk may not ask for more memory than a bounded batch.
#include "laz/points.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <optional>

#include "laz/arithmetic.h"
#include "laz/common.h"
#include "nestlight/octree/error.h"

namespace nestlight::laz {

namespace {
// A chunk is decoded whole, so its claimed point count decides an allocation: refuse claims no
// writer makes (LASzip's default is 50,000 points; COPC writers stay far below this).
constexpr uint32_t kMaxChunkPoints = 1u << 26;
// The same for the records' bytes: points of very long records (extra bytes) may claim less.
constexpr uint64_t kMaxChunkRecordBytes = uint64_t(1) << 30;
}  // namespace

struct LazPoints::Decoders : tbb::enumerable_thread_specific<std::unique_ptr<ChunkDecoder>> {
  using tbb::enumerable_thread_specific<std::unique_ptr<ChunkDecoder>>::enumerable_thread_specific;
};

LazPoints::~LazPoints() = default;

LazPoints::LazPoints(std::shared_ptr<ByteSource> src, LaszipInfo info, uint64_t pointStart,
                     uint64_t dataEnd, uint64_t declaredPoints, bool lenient,
                     std::function<void(std::string)> warn, std::vector<Chunk> hierarchyChunks)
    : src_(std::move(src)),
      info_(std::move(info)),
      recordSize_(info_.recordSize()),
      pointStart_(pointStart),
      dataEnd_(dataEnd),
      lenient_(lenient),
      warn_(std::move(warn)),
      hierarchy_(std::move(hierarchyChunks)),
      decoders_(std::make_unique<Decoders>([this] {
        // One per thread that decodes, made on its first chunk.
        return info_.compressor == Compressor::LayeredChunked ? makeLayeredDecoder(info_)
                                                              : makePointwiseDecoder(info_);
      })) {
  if (info_.compressor == Compressor::Pointwise) {
    // LASzip 1.0: one stream for every point, no chunk table.
    if (declaredPoints > kMaxChunkPoints || declaredPoints * recordSize_ > kMaxChunkRecordBytes)
      fail(pointStart_, "the unchunked LAZ stream (LASzip compressor 1) holds " +
                            std::to_string(declaredPoints) +
                            " points; this reader decodes at most " +
                            std::to_string(kMaxChunkPoints) +
                            " without chunks: recompress with a chunked LASzip");
    tabled_ = true;
    if (declaredPoints)
      chunks_.push_back({pointStart_, dataEnd_ - pointStart_, 0, uint32_t(declaredPoints)});
    points_ = declaredPoints;
    return;
  }
  readChunkTable(declaredPoints);
}

std::string LazPoints::chunkName(size_t i) const {
  const Chunk& c = chunks_[i];
  std::string s = "chunk " + std::to_string(i + 1);
  if (tabled_) s += " of " + std::to_string(chunks_.size());
  if (c.points)
    s += " (points " + std::to_string(c.firstPoint + 1) + "-" +
         std::to_string(c.firstPoint + c.points) + ")";
  return s;
}

void LazPoints::fail(uint64_t at, const std::string& reason) const {
  throw Error(src_->name(), Error::atByte(at), reason);
}

void LazPoints::readChunkTable(uint64_t declared) {
  const uint8_t* d = src_->data();
  const uint64_t size = src_->size();
  const uint64_t chunksStart = pointStart_ + 8;
  if (dataEnd_ < chunksStart)
    fail(pointStart_, "the point data ends before the 8-byte offset of the LAZ chunk table");
  int64_t table = get<int64_t>(d + pointStart_);
  uint64_t tableAt = pointStart_;  // where the offset was read, for messages
  if (table == -1 && size >= 8) {
    tableAt = size - 8;
    table = get<int64_t>(d + tableAt);
  }
  const bool fixed = info_.chunkSize != kVariableChunkSize;

  // Without a table, a COPC hierarchy still says where every chunk is; chunks of a fixed size
  // can be found one after the other, each starting where the previous one's stream ended;
  // other variable-size ones cannot be found.
  auto sequential = [&](const std::string& why) {
    if (!hierarchy_.empty()) {
      warn_(src_->name() + ": " + Error::atByte(tableAt) + ": " + why +
            "; the chunks are read from the COPC hierarchy instead");
      chunks_.clear();
      unreadableAtOpen_ = 0;
      useHierarchy(declared);
      return;
    }
    if (!fixed) fail(tableAt, why + "; a file with variable-size chunks cannot be read without it");
    chunks_.clear();
    unreadableAtOpen_ = 0;
    // Not an error by itself (LASzip reads such files too): a damaged chunk on the way is.
    warn_(src_->name() + ": " + Error::atByte(tableAt) + ": " + why +
          "; chunks are found one after the other (no parallel decoding)");
    tabled_ = false;
    source_ = "sequential";
    points_ = declared;
    if (declared)
      chunks_.push_back(
          {chunksStart, 0, 0, uint32_t(std::min<uint64_t>(declared, info_.chunkSize))});
  };

  if (uint64_t(table) == pointStart_)
    return sequential("the LAZ file has no chunk table (the compressor was interrupted)");
  if (table < int64_t(chunksStart) || uint64_t(table) > size || size - uint64_t(table) < 8)
    return sequential(
        "the LAZ chunk table offset " + std::to_string(table) +
        (table < 0 || uint64_t(table) < chunksStart
             ? " lies before the point data"
             : " points past the end of the file (" + std::to_string(size) + " bytes)"));
  tableStart_ = uint64_t(table);
  const uint32_t version = get<uint32_t>(d + tableStart_);
  if (version != 0)
    fail(tableStart_,
         "unknown LAZ chunk table version " + std::to_string(version) + " (expected 0)");
  const uint32_t n = get<uint32_t>(d + tableStart_ + 4);
  const uint64_t dataBytes = tableStart_ - chunksStart;
  // Every chunk stores its first point raw, so the table cannot list more chunks than fit.
  if (n > dataBytes / std::max<size_t>(recordSize_, 1))
    fail(tableStart_ + 4, "the LAZ chunk table lists " + std::to_string(n) + " chunks, but the " +
                              std::to_string(dataBytes) + " bytes of point data hold at most " +
                              std::to_string(dataBytes / std::max<size_t>(recordSize_, 1)));
  std::vector<uint32_t> counts(n), bytes(n);
  if (n) {
    ArithmeticDecoder dec;
    dec.init(d + tableStart_ + 8, d + size);
    IntegerDecoder ic(32, 2);
    for (uint32_t i = 0; i < n; ++i) {
      if (!fixed)
        counts[i] = static_cast<uint32_t>(ic.decompress(dec, i ? int32_t(counts[i - 1]) : 0, 0));
      bytes[i] = static_cast<uint32_t>(ic.decompress(dec, i ? int32_t(bytes[i - 1]) : 0, 1));
      if (dec.overrun()) {
        const std::string what = "the LAZ chunk table (from byte " + std::to_string(tableStart_) +
                                 ") ends inside the entry of chunk " + std::to_string(i + 1) +
                                 " of " + std::to_string(n);
        if (lenient_ && (fixed || !hierarchy_.empty())) return sequential(what);
        fail(size, what);
      }
    }
  }
  tabled_ = true;

  uint64_t at = chunksStart, first = 0;
  chunks_.reserve(n);
  for (uint32_t i = 0; i < n; ++i) {
    Chunk c;
    c.offset = at;
    c.bytes = bytes[i];
    c.firstPoint = first;
    // Fixed-size chunks are full but for the last, whose count the header's implies.
    c.points = !fixed      ? counts[i]
               : i + 1 < n ? info_.chunkSize
                           : uint32_t(std::min<uint64_t>(info_.chunkSize,
                                                         declared > first ? declared - first : 0));
    if (c.points > kMaxChunkPoints || uint64_t(c.points) * recordSize_ > kMaxChunkRecordBytes)
      fail(c.offset, "chunk " + std::to_string(i + 1) + " of " + std::to_string(n) + " claims " +
                         std::to_string(c.points) +
                         " points, more than this reader decodes at once (" +
                         std::to_string(kMaxChunkPoints) + ")");
    if (c.bytes > tableStart_ - at) {
      const std::string what =
          "chunk " + std::to_string(i + 1) + " of " + std::to_string(n) + " (" +
          std::to_string(c.bytes) + " bytes at byte " + std::to_string(at) +
          ") runs past the start of the chunk table at byte " + std::to_string(tableStart_);
      if (!lenient_) fail(at, what);
      // A damaged table, most likely (one wrong byte garbles every entry after it): the chunks
      // themselves may be intact and can be found without it.
      if (fixed || !hierarchy_.empty()) return sequential(what + "; the chunk table is damaged");
      uint64_t lost = 0;
      for (uint32_t j = i; j < n; ++j) lost += fixed ? 0 : counts[j];
      warn_(src_->name() + ": " + Error::atByte(at) + ": " + what + "; the " +
            std::to_string(lost) +
            " points of it and the following chunks are counted as unreadable");
      unreadableAtOpen_ = lost;
      break;
    }
    chunks_.push_back(c);
    at += c.bytes;
    first += c.points;
  }
  points_ = first;
  if (lenient_ && fixed && n && at != tableStart_ && unreadableAtOpen_ == 0)
    // LASzip writes the chunks back to back and the table right after them.
    return sequential("the chunk sizes of the LAZ chunk table add up to " +
                      std::to_string(at - chunksStart) + " bytes, but the chunks fill the " +
                      std::to_string(dataBytes) + " bytes up to the table: it is damaged");
  if (fixed && n && unreadableAtOpen_ == 0) countLastChunk(declared);
  const uint64_t listed = points_ + unreadableAtOpen_;
  if (listed < declared) {
    const std::string what = "the header declares " + std::to_string(declared) +
                             " points but the " + std::to_string(n) + " LAZ chunks hold " +
                             (fixed ? "at most " : "") + std::to_string(listed);
    if (!lenient_) fail(tableStart_, what + "; the file is truncated or its header is wrong");
    // The declared points no chunk holds are unreadable too: the accounting covers them all.
    unreadableAtOpen_ += declared - listed;
    warn_(src_->name() + ": " + what + "; read the " + std::to_string(points_) +
          " they hold and count the other " + std::to_string(declared - points_) +
          " as unreadable");
  } else if (listed > declared && declaredShort_ == 0) {
    // LASzip trusts the header and drops the rest; every point the chunks hold is read here, and
    // the difference is said.
    warn_(src_->name() + ": the header declares " + std::to_string(declared) +
          " points but the LAZ chunk table lists " + std::to_string(listed) + "; read " +
          std::to_string(listed));
  }
  if (dataEnd_ < tableStart_)
    fail(tableStart_, "the LAZ chunk table at byte " + std::to_string(tableStart_) +
                          " lies after the end of the point data (byte " +
                          std::to_string(dataEnd_) + ")");
  unreadable_ = unreadableAtOpen_;
  if (!hierarchy_.empty()) checkHierarchy();
}

// With a fixed chunk size, every chunk but the last holds chunkSize points and the header's count
// says how many the last one holds. The last chunk is counted (layered chunks store their count;
// pointwise ones are decoded to the end of their bytes): when it holds more than the header says,
// the header is wrong and every point the chunks hold is read. A header that says more is met by
// decoding, which runs dry.
void LazPoints::countLastChunk(uint64_t declared) {
  Chunk& last = chunks_.back();
  const uint64_t before = last.firstPoint;
  const bool layered = info_.compressor == Compressor::LayeredChunked;
  // One chunk decoded at open: a header that understates by less than a chunk is caught too.
  // The chunk size is a claim too: bounded as every chunk's count is.
  const uint32_t most = uint32_t(std::min<uint64_t>(
      {info_.chunkSize, kMaxChunkPoints, kMaxChunkRecordBytes / std::max<size_t>(recordSize_, 1)}));
  RecordBuffer scratch;
  if (!layered) scratch.resize(size_t(most) * recordSize_);
  const ChunkDecoder::PointCount count =
      decoders_->local()->countPoints(src_->data() + last.offset, last.bytes, most, scratch.data());
  if (count.least == 0) return;  // damaged: decoding it will say so
  const uint64_t held = before + count.least;
  if (held <= declared) return;
  std::string how = layered ? "as the last chunk says"
                            : "the last chunk counted by decoding it to the end of its bytes";
  if (count.upTo > count.least)
    how += "; it may hold up to " + std::to_string(count.upTo) +
           " points of which the last cost no bytes, and only the first " +
           std::to_string(count.least) + " are read";
  warn_(src_->name() + ": the header declares " + std::to_string(declared) + " points but the " +
        std::to_string(chunks_.size()) + " LAZ chunks hold " + std::to_string(held) + " (" + how +
        "); read " + std::to_string(held));
  last.points = count.least;
  points_ = held;
  declaredShort_ = held - declared;
}

// COPC lists every chunk in its hierarchy (offset, bytes, points): the same facts as the table.
void LazPoints::checkHierarchy() {
  std::vector<Chunk> h = hierarchy_;
  std::sort(h.begin(), h.end(), [](const Chunk& a, const Chunk& b) { return a.offset < b.offset; });
  size_t matched = 0;
  for (const Chunk& e : h) {
    auto it = std::lower_bound(chunks_.begin(), chunks_.end(), e.offset,
                               [](const Chunk& c, uint64_t o) { return c.offset < o; });
    if (it != chunks_.end() && it->offset == e.offset && it->bytes == e.bytes &&
        it->points == e.points)
      ++matched;
  }
  if (matched != h.size() || h.size() != chunks_.size())
    warn_(src_->name() + ": the COPC hierarchy lists " + std::to_string(h.size()) +
          " chunks, of which " + std::to_string(matched) + " match the " +
          std::to_string(chunks_.size()) + " of the LAZ chunk table; the chunk table is used");
}

void LazPoints::useHierarchy(uint64_t declared) {
  std::vector<Chunk> h = hierarchy_;
  std::sort(h.begin(), h.end(), [](const Chunk& a, const Chunk& b) { return a.offset < b.offset; });
  uint64_t first = 0, end = pointStart_ + 8;
  for (Chunk c : h) {
    if (c.points == 0) continue;
    if (c.offset < end || c.bytes > dataEnd_ || c.offset > dataEnd_ - c.bytes)
      fail(c.offset, "the COPC hierarchy lists a chunk of " + std::to_string(c.bytes) +
                         " bytes at byte " + std::to_string(c.offset) +
                         " that overlaps another or lies outside the point data");
    if (c.points > kMaxChunkPoints || uint64_t(c.points) * recordSize_ > kMaxChunkRecordBytes)
      fail(c.offset, "a COPC chunk claims " + std::to_string(c.points) + " points");
    c.firstPoint = first;
    first += c.points;
    end = c.offset + c.bytes;
    chunks_.push_back(c);
  }
  tabled_ = true;
  source_ = "COPC hierarchy";
  points_ = first;
  if (first != declared) {
    const std::string what = "the header declares " + std::to_string(declared) +
                             " points but the COPC hierarchy lists " + std::to_string(first);
    if (!lenient_ && first < declared) fail(pointStart_, what);
    warn_(src_->name() + ": " + what + "; read " + std::to_string(first));
    if (first < declared) unreadableAtOpen_ = declared - first;
  }
  unreadable_ = unreadableAtOpen_;
  hierarchy_.clear();  // nothing left to cross-check
}

uint64_t LazPoints::decode(const std::vector<size_t>& which, RecordBuffer& out, bool parallel) {
  const uint8_t* d = src_->data();
  auto& pool = *decoders_;
  out.resize(0);
  if (which.empty()) return 0;

  if (!tabled_) {
    // Files without a table: one chunk at a time, each found where the previous one ended (the
    // frontier), or where an earlier pass found it.
    NL_CHECK(which.size() == 1 && which[0] < chunks_.size());
    const size_t i = which[0];
    const bool frontier = i + 1 == chunks_.size();
    out.resize(size_t(chunks_[i].points) * recordSize_);
    size_t used = 0;
    try {
      if (chunks_[i].offset >= dataEnd_)
        throw DecodeError(0, "starts past the end of the point data");
      const uint64_t avail = chunks_[i].bytes ? chunks_[i].bytes : dataEnd_ - chunks_[i].offset;
      used = pool.local()->decode(d + chunks_[i].offset, avail, chunks_[i].points, out.data());
    } catch (const DecodeError& e) {
      // Without a table nothing after a damaged chunk can be found.
      const std::string what = chunkName(i) + ": " + e.what();
      if (!lenient_) fail(chunks_[i].offset + e.offset, what);
      const uint64_t lost = points_ - chunks_[i].firstPoint;
      warn_(src_->name() + ": " + Error::atByte(chunks_[i].offset + e.offset) + ": " + what +
            "; the " + std::to_string(lost) + " points from here on are counted as unreadable");
      unreadable_ += lost;
      out.resize(0);
      return 0;
    }
    if (!frontier) return chunks_[i].points;
    chunks_[i].bytes = used;
    const uint64_t next = chunks_[i].firstPoint + chunks_[i].points;
    if (next < points_)
      chunks_.push_back({chunks_[i].offset + used, 0, next,
                         uint32_t(std::min<uint64_t>(points_ - next, info_.chunkSize))});
    return chunks_[i].points;
  }

  const size_t n = which.size();
  std::vector<uint64_t> at(n + 1, 0);
  for (size_t k = 0; k < n; ++k) at[k + 1] = at[k] + chunks_[which[k]].points;
  out.resize(size_t(at.back()) * recordSize_);
  std::vector<std::optional<DecodeError>> failed(n);
  auto one = [&](size_t k) {
    const Chunk& c = chunks_[which[k]];
    try {
      pool.local()->decode(d + c.offset, c.bytes, c.points,
                           out.data() + size_t(at[k]) * recordSize_);
    } catch (const DecodeError& e) {
      failed[k] = e;
    }
  };
  // Chunks go to the decoders two at a time (see ChunkDecoder::decodePair): about 1.15 times
  // the speed of one at a time on a core (docs/LAZ.md). In parallel, only while there are pairs
  // enough to keep every core busy.
  auto job = [&](size_t k) {
    const Chunk& c = chunks_[which[k]];
    return ChunkDecoder::Job{d + c.offset, c.bytes, c.points,
                             out.data() + size_t(at[k]) * recordSize_};
  };
  auto pair = [&](size_t q) {
    const size_t k = 2 * q;
    if (k + 1 == n) return one(k);
    ChunkDecoder::Outcome a, b;
    pool.local()->decodePair(job(k), job(k + 1), a, b);
    failed[k] = std::move(a.error);
    failed[k + 1] = std::move(b.error);
  };
  const size_t pairs = (n + 1) / 2;
  if (parallel && n > 1) {
    if (pairs >= 2 * size_t(tbb::this_task_arena::max_concurrency()))
      tbb::parallel_for(size_t(0), pairs, size_t(1), pair);
    else
      tbb::parallel_for(size_t(0), n, size_t(1), one);
  } else {
    for (size_t q = 0; q < pairs; ++q) pair(q);
  }
  // Damaged chunks: an error, or (lenient) their points leave the batch and are counted.
  uint64_t kept = at.back();
  size_t write = 0;
  for (size_t k = 0; k < n; ++k) {
    const Chunk& c = chunks_[which[k]];
    const size_t bytes = size_t(c.points) * recordSize_;
    if (failed[k]) {
      const DecodeError& e = *failed[k];
      const std::string what = chunkName(which[k]) + ": " + e.what();
      if (!lenient_) fail(c.offset + e.offset, what);
      {
        std::lock_guard<std::mutex> lock(warnMutex_);
        warn_(src_->name() + ": " + Error::atByte(c.offset + e.offset) + ": " + what + "; its " +
              std::to_string(c.points) + " points are counted as unreadable");
      }
      unreadable_ += c.points;
      kept -= c.points;
      continue;
    }
    const size_t from = size_t(at[k]) * recordSize_;
    if (write != from) std::memmove(out.data() + write, out.data() + from, bytes);
    write += bytes;
  }
  out.resize(write);
  return kept;
}

}  // namespace nestlight::laz
