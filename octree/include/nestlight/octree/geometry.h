// Small geometric value types shared by the converter, the format and the streaming code.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace nestlight {

struct Vec3d {
  double x = 0, y = 0, z = 0;
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  bool operator==(const Vec3d&) const = default;
};

struct Box3d {
  Vec3d min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity()};
  Vec3d max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
            -std::numeric_limits<double>::infinity()};

  bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
  void extend(double x, double y, double z) {
    min.x = std::min(min.x, x), min.y = std::min(min.y, y), min.z = std::min(min.z, z);
    max.x = std::max(max.x, x), max.y = std::max(max.y, y), max.z = std::max(max.z, z);
  }
  void extend(const Box3d& b) {
    if (b.empty()) return;
    extend(b.min.x, b.min.y, b.min.z);
    extend(b.max.x, b.max.y, b.max.z);
  }
  bool contains(double x, double y, double z, double tol = 0) const {
    return x >= min.x - tol && x <= max.x + tol && y >= min.y - tol && y <= max.y + tol &&
           z >= min.z - tol && z <= max.z + tol;
  }
  bool operator==(const Box3d&) const = default;
};

// Integer positions relative to the octree's offset, in units of the octree's scale.
struct Int3 {
  int64_t x = 0, y = 0, z = 0;
  bool operator==(const Int3&) const = default;
};

}  // namespace nestlight
