// Scan readers, as stages (PDAL): open, read the header, stream batches of points, rewind.
//
// A reader never drops a point silently. Points it cannot interpret are errors (file and
// position named); NaN/Inf coordinates pass through so that the builder can count them as
// rejected; a header that disagrees with the data is an error unless ReadOptions::lenient,
// in which case the reader keeps every complete record and reports the disagreement in
// warnings().
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/converters/byte_source.h"
#include "nestlight/octree/attribute.h"
#include "nestlight/octree/geometry.h"

namespace nestlight {

struct SourceHeader {
  std::string path;
  std::string format;                      // "las", "laz", "ply", "pcd", "xyz"
  std::optional<uint64_t> declaredPoints;  // what the header claims, if it claims anything
  std::optional<Box3d> declaredBounds;     // LAS header bounds
  std::optional<Vec3d> scale;              // the source's quantisation (LAS)
  std::optional<Vec3d> offset;
  PointLayout layout;      // attributes this source provides, in batch order
  int rgbBits = 0;         // 8 or 16 when the source has "rgb"; else 0
  nlohmann::json crs;      // {"wkt": "..."} and/or {"geotiff": {...}}; null if none
  nlohmann::json details;  // format facts (version, point format, encoding, ...)
};

struct PointBatch {
  std::vector<double> xyz;     // 3 per point, in the source's world coordinates
  std::vector<uint8_t> attrs;  // header().layout.stride() bytes per point
  // Set by PointReader::readDeferred when the batch is still to be decoded: calling it fills xyz
  // and attrs (on any thread, concurrently with other batches and reads; it may throw Error).
  std::function<void(PointBatch&)> pending;
  size_t pendingPoints = 0;  // how many points it claims to hold (for progress)
  size_t size() const { return xyz.size() / 3; }
  void clear() {
    xyz.clear();
    attrs.clear();
    pending = nullptr;
    pendingPoints = 0;
  }
  // Decodes a deferred batch; nothing when it is decoded already.
  void finish() {
    if (!pending) return;
    auto f = std::move(pending);
    pending = nullptr;
    f(*this);
  }
};

struct ReadOptions {
  // Keep every complete record of a file whose header disagrees with its data, and report the
  // disagreement as a warning instead of failing.
  bool lenient = false;
  // XYZ/PTS/TXT: comma-separated column names, e.g. "x,y,z,r,g,b" or "x,y,z,_,intensity".
  // Known: x y z r g b (0-255) R G B (0-65535) i|intensity nx ny nz classification _ (skip);
  // other names become float attributes. Empty: guessed from the first data line.
  std::string columns;
};

class PointReader {
 public:
  virtual ~PointReader() = default;
  virtual const SourceHeader& header() const = 0;
  // Clears `batch` and fills it with up to `maxPoints` points. Returns false when no point was
  // read because the input is exhausted. Throws nestlight::Error on malformed input.
  virtual bool read(PointBatch& batch, size_t maxPoints) = 0;
  // For planning passes that only need a spatial histogram: reads about every `step`-th point.
  // Returns how many input points each returned point stands for (1 when the reader cannot skip
  // cheaply and returns every point), or 0 at the end of the input.
  virtual size_t readSampled(PointBatch& batch, size_t maxPoints, size_t /*step*/) {
    return read(batch, maxPoints) ? 1 : 0;
  }
  // read() (step 1) or readSampled() that may leave the decoding to batch.finish(), so that a
  // caller with parallel workers decodes batches there (compressed sources) instead of on the
  // reading thread. The reader must outlive the batch's finish(). Compressed sources sample and
  // defer whole chunks: such a batch may hold more than maxPoints when one chunk does.
  virtual size_t readDeferred(PointBatch& batch, size_t maxPoints, size_t step) {
    return step > 1 ? readSampled(batch, maxPoints, step) : (read(batch, maxPoints) ? 1 : 0);
  }
  // Starts again from the first point.
  virtual void rewind() = 0;
  // A job of several ranks reads a large input in parts: into how many units the reader can be
  // restricted (an uncompressed LAS file's records, a LAZ file's chunks where it has a chunk
  // table or COPC hierarchy; 1: it cannot be split), and the restriction
  // to units [first, end), after which reading and rewind() cover those alone (bytesTotal() and
  // bytesConsumed() too; [0, splitUnits()) lifts it). Declared counts, bounds and warnings stay
  // the whole file's.
  virtual uint64_t splitUnits() const { return 1; }
  virtual void restrictTo(uint64_t first, uint64_t end) { (void)first, (void)end; }
  // Header/data disagreements tolerated in lenient mode, and other notes for the metadata.
  virtual std::vector<std::string> warnings() const { return {}; }
  // Points the source declares but could not decode, counted by the builder as rejected: the
  // damaged chunks of a compressed file read with ReadOptions::lenient, since the last rewind().
  virtual uint64_t pointsUnreadable() const { return 0; }
  // Progress, in bytes of the input.
  virtual uint64_t bytesConsumed() const = 0;
  virtual uint64_t bytesTotal() const = 0;
};

// Chooses the reader from the extension (.las .laz .ply .pcd .xyz .pts .txt .csv); LAZ and COPC
// files go through the LAS reader, which decodes their compressed chunks.
std::unique_ptr<PointReader> openReader(const std::string& path, const ReadOptions& options = {});

std::unique_ptr<PointReader> openLas(std::shared_ptr<ByteSource> src, const ReadOptions& o = {});
std::unique_ptr<PointReader> openPly(std::shared_ptr<ByteSource> src, const ReadOptions& o = {});
std::unique_ptr<PointReader> openXyz(std::shared_ptr<ByteSource> src, const ReadOptions& o = {});
// LAS or LAZ: calls `sink(records, n, recordLength)` with every point record exactly as the
// uncompressed file stores it (LAZ chunks decoded on all cores), in file order. Returns the record
// length. For byte-for-byte tests and decode benchmarks.
size_t readLasRecords(std::shared_ptr<ByteSource> src, const ReadOptions& options,
                      const std::function<void(const uint8_t*, size_t, size_t)>& sink,
                      SourceHeader* header = nullptr, std::vector<std::string>* warnings = nullptr);
// PCD goes through PCL, which reads from a path.
std::unique_ptr<PointReader> openPcd(const std::string& path, const ReadOptions& o = {});

}  // namespace nestlight
