#include "nestlight/octree/node_key.h"

#include <xxhash.h>

#include "nestlight/octree/checksum.h"

namespace nestlight {

std::string NodeKey::name() const {
  std::string s(level + 1, 'r');
  for (uint32_t l = 0; l < level; ++l)
    s[l + 1] = static_cast<char>('0' + ancestor(l + 1).childIndex());
  return s;
}

std::optional<NodeKey> NodeKey::parse(std::string_view name) {
  if (name.empty() || name[0] != 'r' || name.size() > 32) return std::nullopt;
  NodeKey k;
  for (size_t i = 1; i < name.size(); ++i) {
    char c = name[i];
    if (c < '0' || c > '7') return std::nullopt;
    k = k.child(c - '0');
  }
  return k;
}

bool NodeKey::operator<(const NodeKey& o) const {
  if (level != o.level) return level < o.level;
  // Morton order within a level, one bit at a time from the top (levels are at most 31).
  for (int b = static_cast<int>(level) - 1; b >= 0; --b) {
    int a = ((x >> b) & 1) << 2 | ((y >> b) & 1) << 1 | ((z >> b) & 1);
    int c = ((o.x >> b) & 1) << 2 | ((o.y >> b) & 1) << 1 | ((o.z >> b) & 1);
    if (a != c) return a < c;
  }
  return false;
}

namespace {
uint64_t spread21(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}
}  // namespace

uint64_t mortonEncode21(uint32_t x, uint32_t y, uint32_t z) {
  return spread21(x) << 2 | spread21(y) << 1 | spread21(z);
}

uint64_t checksum64(const void* data, size_t size) {
  return XXH3_64bits(data, size);
}

}  // namespace nestlight
