#include "nestlight/converters/reader.h"

#include <algorithm>
#include <filesystem>

#include "nestlight/converters/point_writer.h"
#include "nestlight/octree/error.h"

namespace nestlight {

namespace {
std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}
}  // namespace

std::unique_ptr<PointReader> openReader(const std::string& path, const ReadOptions& options) {
  const std::string ext = lowerExtension(path);
  // LAZ and COPC are LAS files whose point records are compressed; the LAS reader decodes them.
  if (ext == ".las" || ext == ".laz") return openLas(mapFile(path), options);
  if (ext == ".ply") return openPly(mapFile(path), options);
  if (ext == ".pcd") return openPcd(path, options);
  if (ext == ".xyz" || ext == ".pts" || ext == ".txt" || ext == ".csv")
    return openXyz(mapFile(path), options);
  throw Error(path, "",
              "unknown point cloud format '" + ext +
                  "'; supported: .las .laz .ply .pcd .xyz .pts .txt .csv");
}

std::unique_ptr<PointWriter> createWriter(const std::string& path, const SourceHeader& header) {
  const std::string ext = lowerExtension(path);
  // As convert and the Potree export do: a missing output folder is made, not an error.
  if (ext == ".las" || ext == ".laz" || ext == ".ply") {
    const std::filesystem::path parent = std::filesystem::path(path).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::exists(parent, ec) &&
        !std::filesystem::create_directories(parent, ec))
      throw Error(path, "", "cannot create its folder " + parent.string() + ": " + ec.message());
  }
  if (ext == ".las") return createLasWriter(path, header);
  if (ext == ".laz") return createLazWriter(path, header);
  if (ext == ".ply") return createPlyWriter(path, header);
  throw Error(path, "", "cannot write '" + ext + "'; supported: .las .laz .ply");
}

}  // namespace nestlight
