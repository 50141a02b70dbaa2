// The builder's subsampling of an inner node: Poisson-disk sampling on a grid of cells of the
// sample radius, or grid sampling, after Schütz, Ohrhallinger, Wimmer, "Fast Out-of-Core Octree
// Generation for Massive Point Clouds", 2020.
#include "builder_passes.h"

namespace nestlight::build_passes {

// Spatially even subsample (Poisson disk or grid) with spacing size/128, widened until the
// sample fits maxNodePoints: a volume-filling scan (a cube of points) would otherwise put
// 128^3 points into one node.
std::vector<char> Builder::sample(const PointBuffer& pts, const NodeKey& key,
                                  const std::vector<uint32_t>& cand) const {
  const double size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * (meta_.cubeSize >> key.level),
                            key.y * (meta_.cubeSize >> key.level),
                            key.z * (meta_.cubeSize >> key.level)};
  double r = size / 128.0;
  std::vector<char> chosen(cand.size());
  for (int attempt = 0;; ++attempt) {
    const size_t limit = opt_.maxNodePoints;
    size_t accepted = opt_.sampling == Sampling::Grid
                          ? sampleGrid(pts, cand, base, r, chosen, limit)
                          : samplePoisson(pts, cand, base, r, chosen, limit);
    if (accepted <= opt_.maxNodePoints || attempt > 60) {
      NL_CHECK(accepted <= opt_.maxNodePoints);
      return chosen;
    }
    // Surfaces thin out with r^2, volumes with r^3: the square root never overshoots.
    r *= std::max(1.05, std::sqrt(double(accepted) / opt_.maxNodePoints));
  }
}

// Both samplers give up once `limit` points are accepted and return an estimate of the total
// they would have accepted, so that an over-full attempt costs only part of a pass.
size_t Builder::samplePoisson(const PointBuffer& pts, const std::vector<uint32_t>& cand,
                              const uint32_t base[3], double r, std::vector<char>& chosen,
                              size_t limit) const {
  // Neighbour cells, own cell first: in dense data most candidates are rejected there.
  static const std::array<std::array<int, 3>, 27> offsets = [] {
    std::array<std::array<int, 3>, 27> o{};
    int n = 1;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (dx || dy || dz) o[n++] = {dx, dy, dz};
    return o;
  }();
  CellMap cells(std::min(cand.size(), limit + 1));
  // Accepted points as (position, next in cell): the distance tests read them in acceptance
  // order, near each other, instead of gathering from the chunk's point array.
  struct Accepted {
    uint32_t p[3];
    int32_t next;
  };
  thread_local std::vector<Accepted> acc;
  acc.clear();
  const double r2 = r * r, inv = 1.0 / r;
  // Occupied cells as a dense bitmap over the cell keys; most neighbour probes end here.
  thread_local std::vector<uint64_t> occupied;
  occupied.assign((kCellSide * kCellSide * kCellSide + 63) / 64, 0);
  size_t accepted = 0;
  for (size_t k = 0; k < cand.size(); ++k) {
    const uint32_t* p = &pts.pos[3 * size_t(cand[k])];
    const double x = p[0] - base[0], y = p[1] - base[1], z = p[2] - base[2];
    const int64_t cx = int64_t(x * inv), cy = int64_t(y * inv), cz = int64_t(z * inv);
    bool ok = true;
    for (const auto& d : offsets) {
      const uint32_t b = cellKey(cx + d[0], cy + d[1], cz + d[2]);
      if (!(occupied[b >> 6] >> (b & 63) & 1)) continue;
      for (int32_t j = cells.find(b); j >= 0; j = acc[j].next) {
        const uint32_t* q = acc[j].p;
        const double ex = double(q[0]) - p[0], ey = double(q[1]) - p[1], ez = double(q[2]) - p[2];
        if (ex * ex + ey * ey + ez * ez < r2) {
          ok = false;
          break;
        }
      }
      if (!ok) break;
    }
    chosen[k] = ok;
    if (!ok) continue;
    if (++accepted > limit) return accepted * cand.size() / (k + 1);
    const uint32_t b = cellKey(cx, cy, cz);
    occupied[b >> 6] |= uint64_t(1) << (b & 63);
    int32_t& head = cells.slot(b);
    acc.push_back({{p[0], p[1], p[2]}, head});
    head = static_cast<int32_t>(acc.size() - 1);
  }
  return accepted;
}

size_t Builder::sampleGrid(const PointBuffer& pts, const std::vector<uint32_t>& cand,
                           const uint32_t base[3], double r, std::vector<char>& chosen,
                           size_t limit) const {
  CellMap cells(std::min(cand.size(), limit + 1));
  const double inv = 1.0 / r;
  size_t accepted = 0;
  for (size_t k = 0; k < cand.size(); ++k) {
    const uint32_t* p = &pts.pos[3 * size_t(cand[k])];
    int32_t& head =
        cells.slot(cellKey(int64_t((p[0] - base[0]) * inv), int64_t((p[1] - base[1]) * inv),
                           int64_t((p[2] - base[2]) * inv)));
    chosen[k] = head < 0;
    if (head < 0) {
      head = 0;
      if (++accepted > limit) return accepted * cand.size() / (k + 1);
    }
  }
  return accepted;
}

}  // namespace nestlight::build_passes
