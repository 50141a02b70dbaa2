// libFuzzer target for the LAZ decoder, two ways in:
// - a whole file (first byte even): the LAS reader on LASzip-compressed data, strict and lenient,
//   streamed, deferred and sampled, then the raw records, so that the VLR, the chunk table, the
//   COPC hierarchy and every chunk decoder see damaged input;
// - a bare chunk (first byte odd): the next byte picks a point format and item versions, the rest
//   is one chunk handed straight to the chunk decoder, which reaches the item decoders' states
//   faster than mutations through a file can; its two halves, as two chunks decoded two at a
//   time, must give what each gives alone (a differential check of the lock-step decoding).
// Either reads, or throws nestlight::Error / laz::DecodeError; it never reads out of bounds,
// hangs, aborts or leaks.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_common.h"
#include "laz/format.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"

namespace {

// Strict: streamed twice (large and small batches); lenient: the deferred path the converter
// takes (sampled, then all) and the raw records. Each decode of a file costs one pass over its
// chunks, so a run stays cheap enough for many executions a second.
void wholeFile(const uint8_t* data, size_t size) {
  try {
    auto reader = nestlight::openLas(nestlight::borrowedSource("fuzz.laz", data, size));
    (void)reader->header().details.dump();
    nestlight::fuzz::readEverything(*reader);
  } catch (const nestlight::Error&) {
  }
  try {
    nestlight::ReadOptions options;
    options.lenient = true;
    auto reader = nestlight::openLas(nestlight::borrowedSource("fuzz.laz", data, size), options);
    nestlight::PointBatch batch;
    for (size_t step : {size_t(8), size_t(1)}) {
      reader->rewind();
      while (reader->readDeferred(batch, 1000, step)) batch.finish();
    }
    size_t records = 0;
    nestlight::readLasRecords(nestlight::borrowedSource("fuzz.laz", data, size), options,
                              [&](const uint8_t*, size_t n, size_t) { records += n; });
  } catch (const nestlight::Error&) {
  }
}

void pairedAsAlone(const nestlight::laz::LaszipInfo& info, const uint8_t* data, size_t size,
                   uint32_t countA);

void bareChunk(const uint8_t* data, size_t size) {
  using namespace nestlight::laz;
  if (size < 2) return;
  const uint8_t pick = data[0];
  LaszipInfo info;
  const int pf = (pick >> 1) % 11;
  const uint16_t extra = (pick >> 5) & 3;  // 0-3 extra bytes
  const bool layered = pf >= 6;
  info.compressor = layered ? Compressor::LayeredChunked : Compressor::PointwiseChunked;
  info.chunkSize = 50000;
  static const std::vector<ItemType> kItems[11] = {
      {ItemType::Point10},
      {ItemType::Point10, ItemType::GpsTime11},
      {ItemType::Point10, ItemType::Rgb12},
      {ItemType::Point10, ItemType::GpsTime11, ItemType::Rgb12},
      {ItemType::Point10, ItemType::GpsTime11},
      {ItemType::Point10, ItemType::GpsTime11, ItemType::Rgb12},
      {ItemType::Point14},
      {ItemType::Point14, ItemType::Rgb14},
      {ItemType::Point14, ItemType::RgbNir14},
      {ItemType::Point14},
      {ItemType::Point14, ItemType::RgbNir14}};
  static const uint16_t kSizes[15] = {0, 0, 0, 0, 0, 0, 20, 8, 6, 29, 30, 6, 8, 29, 0};
  // Item versions from the top bits of the count byte: 1 or 2 pointwise, 2 to 4 layered.
  const uint16_t version =
      layered ? uint16_t(2 + (data[1] >> 6) % 3) : uint16_t(1 + ((data[1] >> 6) & 1));
  for (ItemType t : kItems[pf]) info.items.push_back({t, kSizes[static_cast<int>(t)], version});
  if (extra) info.items.push_back({layered ? ItemType::Byte14 : ItemType::Byte, extra, version});
  const uint32_t count = 1 + data[1] % 64;
  std::vector<uint8_t> out(size_t(count) * info.recordSize());
  try {
    auto dec = layered ? makeLayeredDecoder(info) : makePointwiseDecoder(info);
    // Twice: a decoder object is reused for many chunks and must reset all its state.
    dec->decode(data + 2, size - 2, count, out.data());
    dec->decode(data + 2, size - 2, count, out.data());
  } catch (const DecodeError& e) {
    if (e.offset > size) __builtin_trap();  // offsets lie inside the chunk or at its end
  }
  pairedAsAlone(info, data + 2, size - 2, count);
}

// The two halves of the chunk data as two chunks of different counts: decoded two at a time
// (ChunkDecoder::decodePair, symbols interleaved), each gives exactly what it gives alone: the
// same records and bytes used, or the same error at the same byte.
void pairedAsAlone(const nestlight::laz::LaszipInfo& info, const uint8_t* data, size_t size,
                   uint32_t countA) {
  using namespace nestlight::laz;
  const size_t half = size / 2;
  const ChunkDecoder::Job jobs[2] = {{data, half, countA, nullptr},
                                     {data + half, size - half, uint32_t(1 + size % 64), nullptr}};
  auto dec = info.compressor == Compressor::LayeredChunked ? makeLayeredDecoder(info)
                                                           : makePointwiseDecoder(info);
  std::vector<uint8_t> alone[2], paired[2];
  ChunkDecoder::Outcome want[2], got[2];
  for (int k = 0; k < 2; ++k) {
    alone[k].assign(size_t(jobs[k].count) * info.recordSize(), 0);
    paired[k].assign(alone[k].size(), 0);
    try {
      want[k].used = dec->decode(jobs[k].data, jobs[k].size, jobs[k].count, alone[k].data());
    } catch (const DecodeError& e) {
      want[k].error = e;
    }
  }
  ChunkDecoder::Job a = jobs[0], b = jobs[1];
  a.out = paired[0].data();
  b.out = paired[1].data();
  dec->decodePair(a, b, got[0], got[1]);
  for (int k = 0; k < 2; ++k) {
    if (bool(want[k].error) != bool(got[k].error)) __builtin_trap();
    if (want[k].error) {
      if (std::string(want[k].error->what()) != got[k].error->what() ||
          want[k].error->offset != got[k].error->offset)
        __builtin_trap();
    } else if (want[k].used != got[k].used || alone[k] != paired[k]) {
      __builtin_trap();
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  if (data[0] & 1)
    bareChunk(data + 1, size - 1);
  else
    wholeFile(data + 1, size - 1);
  return 0;
}
