// `nestlight export`: writes the points of an octree (all, or one level) to LAS or PLY.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

namespace nestlight {

// Returns the number of points written. Positions are offset + integer * scale, so a LAS file
// written with the octree's scale and offset holds exactly the stored integers.
uint64_t exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                      std::optional<uint32_t> level = std::nullopt);

}  // namespace nestlight
