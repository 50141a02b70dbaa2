// Writers for `nestlight export` and `nestlight generate`: LAS, LAZ and PLY.
#pragma once

#include <memory>
#include <string>

#include "nestlight/converters/reader.h"

namespace nestlight {

class PointWriter {
 public:
  virtual ~PointWriter() = default;
  // `batch` follows the layout of the header given at creation.
  virtual void write(const PointBatch& batch) = 0;
  // Finishes the file (header counts and bounds); the file appears atomically under its name.
  virtual void close() = 0;
};

// `header.layout` says which attributes to write; LAS fields it knows by name (see docs/FORMAT.md)
// go into the point record, the rest into LAS 1.4 extra bytes. `header.scale`/`offset` set the
// LAS quantisation (default 0.001 and the first point). `header.crs` is written as a WKT VLR.
std::unique_ptr<PointWriter> createLasWriter(const std::string& path, const SourceHeader& header);
// LAZ (LASzip 2, pointwise chunked): as createLasWriter, for point formats 0-3 (with extra
// bytes); points that need LAS 1.4 formats 6-8 are refused. Compressed at close().
std::unique_ptr<PointWriter> createLazWriter(const std::string& path, const SourceHeader& header);
// Binary little-endian PLY; `header.rgbBits` == 8 writes uchar colour, else ushort.
std::unique_ptr<PointWriter> createPlyWriter(const std::string& path, const SourceHeader& header,
                                             bool ascii = false);
// Chooses by extension (.las, .laz, .ply).
std::unique_ptr<PointWriter> createWriter(const std::string& path, const SourceHeader& header);

}  // namespace nestlight
