// LAZ output (laz_writer.cpp). Private to converters/src.
#pragma once

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "laz/format.h"

namespace nestlight::laz {

inline constexpr uint32_t kChunkPoints = 50000;

// The compressed point data of a LAZ file, written while the records arrive: records are held
// until a group of chunks is full, the group is encoded on all cores and appended, so memory
// stays at a group (kGroupChunks chunks of records) and nothing uncompressed reaches the disk.
// Point formats 0-3 become LASzip 2's pointwise chunked format, 6-8 LASzip 3's layered chunked
// format; other formats throw nestlight::Error naming `nameForErrors`.
class ChunkWriter {
 public:
  static constexpr uint32_t kGroupChunks = 16;

  ChunkWriter(int pointFormat, size_t recordLength, std::string nameForErrors);
  ~ChunkWriter();
  ChunkWriter(const ChunkWriter&) = delete;
  ChunkWriter& operator=(const ChunkWriter&) = delete;

  const LaszipInfo& info() const { return info_; }
  // The LASzip VLR (header and payload), to be the file's last VLR.
  std::vector<uint8_t> vlr() const { return vlrFor(info_); }
  // The same without a writer (no encoders made): what a LAS header being planned needs.
  static std::vector<uint8_t> vlrFor(int pointFormat, size_t recordLength,
                                     const std::string& nameForErrors);
  static std::vector<uint8_t> vlrFor(const LaszipInfo& info);
  // The point data starts at byte `pointStart` of `f` (the header's offset to point data): the
  // chunk table's offset goes there, the chunks after it.
  void begin(std::FILE* f, std::string fileName, uint64_t pointStart);
  void add(const uint8_t* records, size_t count);
  // Encodes what is held, appends the chunk table and fills in its offset. `f` stays open, its
  // position unspecified.
  void finish();
  uint64_t points() const { return points_; }

 private:
  struct Encoders;
  void flush(bool all);
  void put(const void* p, size_t n);

  LaszipInfo info_;
  size_t recordLength_;
  std::string name_, file_;
  std::unique_ptr<Encoders> encoders_;
  std::FILE* f_ = nullptr;
  uint64_t tableSlot_ = 0, at_ = 0, points_ = 0;
  std::vector<uint8_t> pending_;
  std::vector<uint32_t> chunkBytes_;
};

// Writes the uncompressed LAS file `lasPath` (point format 0-3 or 6-8, no EVLRs) compressed to
// `lazPath`. Errors name `nameForErrors`.
void compressLas(const std::string& lasPath, const std::string& lazPath,
                 const std::string& nameForErrors);

}  // namespace nestlight::laz
