// LAZ output (laz_writer.cpp). Private to converters/src.
#pragma once

#include <string>

namespace nestlight::laz {

// Writes the uncompressed LAS file `lasPath` (point format 0-3, no EVLRs) compressed to
// `lazPath` (LASzip 2, pointwise chunked). Errors name `nameForErrors`.
void compressLas(const std::string& lasPath, const std::string& lazPath,
                 const std::string& nameForErrors);

}  // namespace nestlight::laz
