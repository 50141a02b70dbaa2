// LAZ output (laz_writer.cpp). Private to converters/src.
#pragma once

#include <string>

namespace nestlight::laz {

// Writes the uncompressed LAS file `lasPath` (point format 0-3 or 6-8, no EVLRs) compressed to
// `lazPath` (formats 0-3: LASzip 2, pointwise chunked; 6-8: LASzip 3, layered chunked). Errors
// name `nameForErrors`.
void compressLas(const std::string& lasPath, const std::string& lazPath,
                 const std::string& nameForErrors);

}  // namespace nestlight::laz
