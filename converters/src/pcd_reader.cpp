// Placeholder; the PCL-backed reader replaces it.
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
namespace nestlight {
std::unique_ptr<PointReader> openPcd(const std::string& path, const ReadOptions&) {
  throw Error(path, "", "PCD reader not built");
}
}  // namespace nestlight
