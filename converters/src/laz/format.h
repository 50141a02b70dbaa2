// Facts of the LAZ format shared by the LAZ chunk decoders and the LAS/LAZ reader. Private to
// converters/src.
//
// The format is specified by the LASzip reference implementation (Isenburg, "LASzip: lossless
// compression of LiDAR data", PE&RS 79(2), 2013, and LASzip 3.x for the layered compressor of LAS
// 1.4 point formats 6-10): a LAS file whose point format byte has bit 7 set, a VLR "laszip
// encoded"/22204 that lists the compressor and the items of each record, and point data made of
// chunks of independently coded points. Chunked files start the point data with the 64-bit
// offset of a chunk table (an arithmetic-coded list of each chunk's point count and byte size).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace nestlight::laz {

inline constexpr uint16_t kLaszipRecordId = 22204;
inline constexpr const char* kLaszipUserId = "laszip encoded";
inline constexpr uint32_t kVariableChunkSize = 0xFFFFFFFFu;

enum class Compressor : uint16_t {
  None = 0,
  Pointwise = 1,         // one stream for the whole file
  PointwiseChunked = 2,  // LASzip 2: chunks of points, one stream each
  LayeredChunked = 3,    // LASzip 3 (formats 6-10): chunks, one stream per field layer
};

enum class ItemType : uint16_t {
  Byte = 0,  // extra bytes of formats 0-5
  Short = 1,
  Int = 2,
  Long = 3,
  Float = 4,
  Double = 5,
  Point10 = 6,       // the 20 bytes every format 0-5 record starts with
  GpsTime11 = 7,     // 8 bytes
  Rgb12 = 8,         // 6 bytes
  WavePacket13 = 9,  // 29 bytes
  Point14 = 10,      // the 30 bytes every format 6-10 record starts with
  Rgb14 = 11,
  RgbNir14 = 12,
  WavePacket14 = 13,
  Byte14 = 14,  // extra bytes of formats 6-10
};

struct Item {
  ItemType type;
  uint16_t size;
  uint16_t version;
};

std::string itemName(ItemType t);

// The items LASzip writes for point format `pf` (0-10) with `extraBytes` extra bytes (BYTE or
// BYTE14 last), all of `version`; none for an unknown format.
std::vector<Item> itemsFor(int pf, size_t extraBytes, uint16_t version);

// The LASzip VLR's payload.
struct LaszipInfo {
  Compressor compressor = Compressor::None;
  uint16_t coder = 0;  // 0: arithmetic, the only one defined
  uint8_t versionMajor = 0, versionMinor = 0;
  uint16_t versionRevision = 0;
  uint32_t options = 0;
  uint32_t chunkSize = 0;  // points per chunk, or kVariableChunkSize
  std::vector<Item> items;
  size_t recordSize() const {
    size_t s = 0;
    for (const Item& i : items) s += i.size;
    return s;
  }
};

// Parses and checks the VLR payload against the point format and record length of the header.
// Returns an empty string on success, else what is wrong (the caller names file and offset).
std::string parseLaszipVlr(const uint8_t* data, size_t length, int pointFormat, size_t recordLength,
                           LaszipInfo& out);

// A damaged chunk: `offset` is relative to the chunk's first byte.
class DecodeError : public std::runtime_error {
 public:
  DecodeError(uint64_t offset, const std::string& what)
      : std::runtime_error(what), offset(offset) {}
  uint64_t offset;
};

// Decodes chunks of one file's point records. Not thread-safe: each thread makes its own (they
// hold the adaptive models of one chunk).
class ChunkDecoder {
 public:
  virtual ~ChunkDecoder() = default;
  // Decodes the `count` points of the chunk stored in [data, data + size) into `out`, LAS point
  // records of `recordSize` bytes back to back (exactly the bytes of the uncompressed file).
  // Returns the bytes the chunk used (for files without a chunk table, where the next chunk
  // starts there). Throws DecodeError when the chunk is damaged: its bytes end before its points
  // do, a count inside the chunk disagrees, or a field cannot be decoded.
  virtual size_t decode(const uint8_t* data, size_t size, uint32_t count, uint8_t* out) = 0;

  // How many points the chunk in [data, data + size) holds, at most `most`, for chunks whose
  // count nothing else records (the last chunk of a fixed chunk size, when the header's count
  // is wrong). Layered chunks store their count. A pointwise chunk is decoded into `scratch`
  // (`most` records) until its arithmetic stream is used up: the encoder's padding makes the
  // bytes consumed after the last point equal the stream's length, so `least` is the first count
  // that consumes the whole stream; points that cost no new bytes may follow it without running
  // dry, up to `upTo`. {0, 0} when the chunk cannot hold its first point.
  struct PointCount {
    uint32_t least = 0, upTo = 0;
  };
  virtual PointCount countPoints(const uint8_t* data, size_t size, uint32_t most,
                                 uint8_t* scratch) = 0;

  struct Job {
    const uint8_t* data;
    size_t size;
    uint32_t count;
    uint8_t* out;
  };
  struct Outcome {
    size_t used = 0;
    std::optional<DecodeError> error;
    bool lockstep = false;  // decoded in lock step with the other chunk (else one by one)
  };
  // Decodes two chunks, each exactly as decode() would (the same records, bytes used and
  // errors). Decoders whose symbols can interleave the two arithmetic streams do so: one stream
  // is a serial chain of divisions and table lookups, two overlap in the processor.
  virtual void decodePair(const Job& a, const Job& b, Outcome& ra, Outcome& rb) {
    decodeOne(a, ra);
    decodeOne(b, rb);
  }

 protected:
  void decodeOne(const Job& j, Outcome& r) {
    try {
      r.used = decode(j.data, j.size, j.count, j.out);
    } catch (const DecodeError& e) {
      r.error = e;
    }
  }
};

// Encodes chunks of one file's point records (laz_writer.cpp, laz_layered_encoder.cpp). Not
// thread-safe: each thread makes its own.
class ChunkEncoder {
 public:
  virtual ~ChunkEncoder() = default;
  // Appends nothing: `out` becomes the chunk of the `count` records (as decode() reads it).
  virtual void encode(const uint8_t* records, size_t count, std::vector<uint8_t>& out) = 0;
};
// The layered compressor's encoder: POINT14, then RGB14, RGBNIR14 or BYTE14, all version 3.
std::unique_ptr<ChunkEncoder> makeLayeredEncoder(const LaszipInfo& info);

// Compressors 1 and 2 with items of versions 1 and 2 (point formats 0-5).
std::unique_ptr<ChunkDecoder> makePointwiseDecoder(const LaszipInfo& info);
// Compressor 3 with items of version 3 (point formats 6-10).
std::unique_ptr<ChunkDecoder> makeLayeredDecoder(const LaszipInfo& info);

}  // namespace nestlight::laz
