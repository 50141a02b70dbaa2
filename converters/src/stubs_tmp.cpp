// Temporary stubs so the tree links while readers are written; each is removed as its real
// implementation lands.
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
namespace nestlight {
std::unique_ptr<PointReader> openLas(std::shared_ptr<ByteSource> s, const ReadOptions&) { throw Error(s->name(), "", "LAS stub"); }
std::unique_ptr<PointReader> openPly(std::shared_ptr<ByteSource> s, const ReadOptions&) { throw Error(s->name(), "", "PLY stub"); }
std::unique_ptr<PointReader> openXyz(std::shared_ptr<ByteSource> s, const ReadOptions&) { throw Error(s->name(), "", "XYZ stub"); }
std::unique_ptr<PointWriter> createLasWriter(const std::string& p, const SourceHeader&) { throw Error(p, "", "LAS writer stub"); }
std::unique_ptr<PointWriter> createPlyWriter(const std::string& p, const SourceHeader&, bool) { throw Error(p, "", "PLY writer stub"); }
}  // namespace nestlight
