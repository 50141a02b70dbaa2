#include "nestlight/converters/synthetic_octree.h"

#include <chrono>
#include <cstdio>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight {

namespace fs = std::filesystem;

fs::path ensureSyntheticOctree(uint64_t points, const fs::path& dir, bool quiet) {
  if (fs::exists(dir / "metadata.json")) {
    try {
      if (OctreeReader(dir).metadata().points == points) return dir;
    } catch (const Error&) {
      // Damaged or of another version: rebuilt below.
    }
  }
  SyntheticSpec spec;
  spec.points = points;
  spec.seed = 42;
  spec.intensity = false;
  BuildOptions o;
  o.output = dir;
  o.overwrite = true;
  o.progress = ProgressMode::Quiet;
  std::vector<std::unique_ptr<PointReader>> sources;
  sources.push_back(openSynthetic(spec));
  if (!quiet)
    std::fprintf(stderr, "generating and converting %llu synthetic points into %s\n",
                 (unsigned long long)points, dir.c_str());
  const auto t = std::chrono::steady_clock::now();
  buildOctree(std::move(sources), o);
  if (!quiet)
    std::fprintf(stderr, "  converted in %.1f s\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
  return dir;
}

}  // namespace nestlight
