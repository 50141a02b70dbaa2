// Shared by the reader fuzz targets. Header-only: each tests/fuzz/fuzz_*.cpp builds on its own.
#pragma once

#include <cstddef>

#include "nestlight/converters/reader.h"

namespace nestlight::fuzz {

// Reads every point of `reader` twice, in large batches and then, after rewind(), in small ones,
// and asks for its warnings. Traps when a batch breaks the PointReader contract: empty although
// read() returned true, larger than asked for, or without the layout's stride of attribute bytes
// per point. Malformed input may throw nestlight::Error, which the caller catches.
inline void readEverything(PointReader& reader) {
  constexpr size_t kLarge = 4096, kSmall = 7;
  const size_t stride = reader.header().layout.stride();
  PointBatch batch;
  while (reader.read(batch, kLarge))
    if (batch.size() == 0 || batch.size() > kLarge || batch.attrs.size() != batch.size() * stride)
      __builtin_trap();
  reader.rewind();
  while (reader.read(batch, kSmall)) {
  }
  (void)reader.warnings();
}

}  // namespace nestlight::fuzz
