// A synthetic scan converted straight into an octree, for stress runs and benchmarks that need
// an octree of a given size without a scan file in between.
#pragma once

#include <cstdint>
#include <filesystem>

namespace nestlight {

// Converts `points` points of the synthetic scene (`nestlight generate`'s default shape, seed 42,
// no intensity) into `dir`, and returns `dir`. An octree already there with exactly that many
// points is reused. `quiet` silences the two progress lines on stderr.
std::filesystem::path ensureSyntheticOctree(uint64_t points, const std::filesystem::path& dir,
                                            bool quiet = false);

}  // namespace nestlight
