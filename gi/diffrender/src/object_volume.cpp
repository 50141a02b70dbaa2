// Solid voxelisation of the inserted meshes (nestlight/gi/diffrender/object_volume.h): Eisemann
// and Décoret, "Single-pass GPU solid voxelization for real-time applications" (2008), done on
// the CPU: a voxel centre is inside when the line along +z through it crosses the surface an odd
// number of times below it (their XOR of slabs, here as sorted crossings per column). The surface
// shell: Akenine-Möller, "Fast 3D triangle-box overlap testing" (2001), the separating axis test.
#include "nestlight/gi/diffrender/object_volume.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <tuple>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

size_t ObjectVolume::bytes() const {
  return occupancy.size() * sizeof(uint8_t) + surface.size() * sizeof(uint32_t);
}

// Named, apart from anonymous: the files of a library are compiled in batches (unity builds), and
// file-local names of the method's files would meet these.
namespace voxelization {
namespace {

constexpr uint64_t kMaxVoxels = uint64_t(1) << 31;
// A flat axis (extent below this fraction of the largest) takes the other axes' voxel size.
constexpr double kFlat = 1e-6;
// The shell's tie rule, in voxels (of the smallest voxel side): triangles move this far inward
// along their normal and voxel boxes shrink by half of it per side, so that a face lying exactly
// on a voxel boundary marks the one voxel layer inside it, not both layers. Every mesh's extreme
// faces lie on such a boundary (the grid is the bounds padded by one voxel): without the rule a
// box would mark the padding, and the padding would not be empty.
constexpr double kInwardShift = 2e-3, kBoxShrink = 1e-3;

struct Triangle {
  std::array<glm::dvec3, 3> p;
  glm::dvec3 normal;  // outward, length = area
};

struct PreparedMesh {
  std::vector<Triangle> triangles;
};

struct Grid {
  glm::ivec3 n;
  glm::dvec3 lo, d;

  double centre(int axis, int k) const { return lo[axis] + (k + 0.5) * d[axis]; }
  size_t index(int x, int y, int z) const {
    return size_t(x) + size_t(n.x) * (size_t(y) + size_t(n.y) * size_t(z));
  }
  // A conservative index range [first, last] of voxels along `axis` whose extent may meet
  // [a, b] widened by one voxel each side; empty (first > last) when outside the grid.
  std::pair<int, int> span(int axis, double a, double b) const {
    const double fa = std::floor((a - lo[axis]) / d[axis]) - 1;
    const double fb = std::floor((b - lo[axis]) / d[axis]) + 1;
    const double top = n[axis] - 1;
    return {int(std::clamp(fa, 0.0, top + 1)), int(std::clamp(fb, -1.0, top))};
  }
};

std::string meshName(const std::vector<VolumeMesh>& meshes, size_t i) {
  return meshes[i].name.empty() ? "meshes[" + std::to_string(i) + "]" : meshes[i].name;
}

void validate(const std::vector<VolumeMesh>& meshes, glm::ivec3 size) {
  if (size.x < 1 || size.y < 1 || size.z < 1)
    throw Error("object volume: size " + std::to_string(size.x) + "x" + std::to_string(size.y) +
                "x" + std::to_string(size.z) + " needs at least one voxel per axis");
  const uint64_t voxels = uint64_t(size.x) * uint64_t(size.y) * uint64_t(size.z);
  if (voxels > kMaxVoxels)
    throw Error("object volume: size " + std::to_string(size.x) + "x" + std::to_string(size.y) +
                "x" + std::to_string(size.z) + " is " + std::to_string(voxels) +
                " voxels, more than 2^31");
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::string name = meshName(meshes, i);
    if (!meshes[i].mesh) throw Error("object volume: " + name + ": no mesh");
    if (meshes[i].material >= 255)
      throw Error("object volume: " + name + ": material " + std::to_string(meshes[i].material) +
                  " does not fit the surface's alpha (at most 254)");
  }
}

// The meshes' triangles in the local frame, without those that cannot be voxelised; extends
// [bmin, bmax] by their corners.
std::vector<PreparedMesh> prepare(const std::vector<VolumeMesh>& meshes, glm::dvec3& bmin,
                                  glm::dvec3& bmax, uint64_t& skipped) {
  std::vector<PreparedMesh> out(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m) {
    const TriangleMesh& mesh = *meshes[m].mesh;
    const glm::dmat4 xf(meshes[m].localFromObject);
    // A mirroring transform turns counter-clockwise corners clockwise: the outward normal flips.
    const double mirror = glm::determinant(glm::dmat3(xf)) < 0 ? -1.0 : 1.0;
    const size_t count = mesh.indices.size() / 3;
    out[m].triangles.reserve(count);
    for (size_t t = 0; t < count; ++t) {
      Triangle tri;
      bool ok = true;
      for (int c = 0; c < 3 && ok; ++c) {
        const uint32_t v = mesh.indices[3 * t + c];
        if (v >= mesh.positions.size()) {
          ok = false;
          break;
        }
        tri.p[c] = glm::dvec3(xf * glm::dvec4(glm::dvec3(mesh.positions[v]), 1.0));
        ok = std::isfinite(tri.p[c].x) && std::isfinite(tri.p[c].y) && std::isfinite(tri.p[c].z);
      }
      if (ok) {
        tri.normal = 0.5 * mirror * glm::cross(tri.p[1] - tri.p[0], tri.p[2] - tri.p[0]);
        const double area = glm::length(tri.normal);
        ok = area > 0 && std::isfinite(area);
      }
      if (!ok) {
        ++skipped;
        continue;
      }
      for (const glm::dvec3& p : tri.p) {
        bmin = glm::min(bmin, p);
        bmax = glm::max(bmax, p);
      }
      out[m].triangles.push_back(tri);
    }
  }
  return out;
}

// The grid over [bmin, bmax]: one voxel of padding each side where an axis has 3 voxels or more.
Grid makeGrid(glm::dvec3 bmin, glm::dvec3 bmax, glm::ivec3 size) {
  Grid g{size, glm::dvec3(-0.5), glm::dvec3(1.0) / glm::dvec3(size)};
  const glm::dvec3 ext = bmax - bmin;
  const double largest = std::max({ext.x, ext.y, ext.z});
  if (!(largest > 0)) return g;  // no triangles: the empty grid over [-0.5, 0.5]^3
  std::array<bool, 3> flat{};
  double widest = 0;
  for (int a = 0; a < 3; ++a) {
    flat[a] = ext[a] <= kFlat * largest;
    if (!flat[a]) {
      g.d[a] = ext[a] / std::max(size[a] - 2, 1);
      widest = std::max(widest, g.d[a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (flat[a]) g.d[a] = widest;
    // Exactly bmin - d where the axis is padded, so that the faces of a mesh on its bounds fall
    // exactly on voxel boundaries; centred otherwise.
    g.lo[a] = (!flat[a] && size[a] >= 3) ? bmin[a] - g.d[a]
                                         : 0.5 * (bmin[a] + bmax[a]) - 0.5 * size[a] * g.d[a];
    const float lo = float(g.lo[a]), hi = float(g.lo[a] + size[a] * g.d[a]);
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
      throw Error("object volume: the meshes' bounds [" + std::to_string(bmin[a]) + ", " +
                  std::to_string(bmax[a]) + "] along axis " + std::to_string(a) +
                  " do not fit a grid of floats");
  }
  return g;
}

// The column test, exactly antisymmetric: the edge function of (a, b) is that of (b, a) negated
// bit for bit (both are computed from the same ordered pair), so two triangles sharing an edge
// never both claim, nor both miss, a column on it.
double edgeFunction(glm::dvec2 a, glm::dvec2 b, glm::dvec2 p) {
  const bool swap = b.x < a.x || (b.x == a.x && b.y < a.y);
  if (swap) std::swap(a, b);
  const double e = (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
  return swap ? -e : e;
}

// A column exactly on an edge of a counter-clockwise triangle belongs to it when the edge is a
// left or top edge: the column is judged as if moved by (eps, -eps^2), one infinitesimal
// perturbation for every edge of every triangle, so a column through a shared edge or vertex
// meets the surface as often as a column beside it does.
bool claims(double e, glm::dvec2 a, glm::dvec2 b) {
  if (e != 0) return e > 0;
  const double dy = b.y - a.y, dx = b.x - a.x;
  return dy < 0 || (dy == 0 && dx < 0);
}

// Where the column's line crosses the (counter-clockwise in xy) triangle, if it does.
bool crossing(const Triangle& t, glm::dvec2 p, double& z) {
  const glm::dvec2 a(t.p[0]), b(t.p[1]), c(t.p[2]);
  const double w0 = edgeFunction(b, c, p), w1 = edgeFunction(c, a, p), w2 = edgeFunction(a, b, p);
  if (!claims(w0, b, c) || !claims(w1, c, a) || !claims(w2, a, b)) return false;
  const double sum = w0 + w1 + w2;
  if (!(sum > 0)) return false;
  z = (w0 * t.p[0].z + w1 * t.p[1].z + w2 * t.p[2].z) / sum;
  return true;
}

// The first voxel along z whose centre is at or above `z`.
int firstAtOrAbove(const Grid& g, double z) {
  int k = int(std::clamp(std::ceil((z - g.lo.z) / g.d.z - 0.5), 0.0, double(g.n.z)));
  while (k > 0 && g.centre(2, k - 1) >= z) --k;
  while (k < g.n.z && g.centre(2, k) < z) ++k;
  return k;
}

// Fills the interior of one mesh into `occupancy`; returns how many columns were open.
uint64_t fillParity(const Grid& g, const PreparedMesh& mesh, std::vector<uint8_t>& occupancy) {
  // Triangles seen from +z, counter-clockwise; those seen edge-on cross no column.
  std::vector<Triangle> tris;
  tris.reserve(mesh.triangles.size());
  for (Triangle t : mesh.triangles) {
    const double area = edgeFunction(glm::dvec2(t.p[0]), glm::dvec2(t.p[1]), glm::dvec2(t.p[2]));
    if (area == 0) continue;
    if (area < 0) std::swap(t.p[1], t.p[2]);
    tris.push_back(t);
  }
  // Triangles by the rows (y) their xy bounds meet, as offsets into one list.
  std::vector<size_t> offsets(size_t(g.n.y) + 1, 0);
  std::vector<uint32_t> rows;
  std::vector<std::pair<int, int>> spans(tris.size());
  for (size_t i = 0; i < tris.size(); ++i) {
    const auto& p = tris[i].p;
    spans[i] = g.span(1, std::min({p[0].y, p[1].y, p[2].y}), std::max({p[0].y, p[1].y, p[2].y}));
    for (int y = spans[i].first; y <= spans[i].second; ++y) ++offsets[size_t(y) + 1];
  }
  for (size_t y = 0; y < size_t(g.n.y); ++y) offsets[y + 1] += offsets[y];
  rows.resize(offsets.back());
  {
    std::vector<size_t> fill(offsets.begin(), offsets.end() - 1);
    for (size_t i = 0; i < tris.size(); ++i)
      for (int y = spans[i].first; y <= spans[i].second; ++y) rows[fill[size_t(y)]++] = uint32_t(i);
  }

  std::atomic<uint64_t> open{0};
  tbb::parallel_for(tbb::blocked_range<int>(0, g.n.y), [&](const tbb::blocked_range<int>& r) {
    std::vector<std::pair<int, double>> hits;  // (column x, crossing z)
    uint64_t localOpen = 0;
    for (int y = r.begin(); y != r.end(); ++y) {
      hits.clear();
      const double py = g.centre(1, y);
      for (size_t k = offsets[size_t(y)]; k < offsets[size_t(y) + 1]; ++k) {
        const Triangle& t = tris[rows[k]];
        // The x extent of the triangle on this row, from the edges that reach it.
        double x0 = std::numeric_limits<double>::infinity(), x1 = -x0;
        for (int e = 0; e < 3; ++e) {
          const glm::dvec3 &a = t.p[size_t(e)], &b = t.p[size_t((e + 1) % 3)];
          if (py < std::min(a.y, b.y) || py > std::max(a.y, b.y)) continue;
          const double x = a.y == b.y ? a.x : a.x + (py - a.y) * (b.x - a.x) / (b.y - a.y);
          x0 = std::min({x0, x, a.y == b.y ? b.x : x});
          x1 = std::max({x1, x, a.y == b.y ? b.x : x});
        }
        if (!(x0 <= x1)) continue;
        const auto [first, last] = g.span(0, x0, x1);
        for (int x = first; x <= last; ++x) {
          double z;
          if (crossing(t, glm::dvec2(g.centre(0, x), py), z)) hits.emplace_back(x, z);
        }
      }
      std::sort(hits.begin(), hits.end());
      for (size_t i = 0; i < hits.size();) {
        size_t j = i;
        while (j < hits.size() && hits[j].first == hits[i].first) ++j;
        if ((j - i) % 2 == 1) {
          ++localOpen;
        } else {
          for (size_t h = i; h < j; h += 2) {
            const int z0 = firstAtOrAbove(g, hits[h].second);
            const int z1 = firstAtOrAbove(g, hits[h + 1].second);
            for (int z = z0; z < z1; ++z) occupancy[g.index(hits[i].first, y, z)] = 255;
          }
        }
        i = j;
      }
    }
    open += localOpen;
  });
  return open;
}

// Akenine-Möller's separating axis test of a triangle (relative to the box's centre) against a
// box of half size h centred at the origin.
bool overlapsBox(const std::array<glm::dvec3, 3>& v, glm::dvec3 h) {
  for (int a = 0; a < 3; ++a) {
    const double lo = std::min({v[0][a], v[1][a], v[2][a]});
    const double hi = std::max({v[0][a], v[1][a], v[2][a]});
    if (lo > h[a] || hi < -h[a]) return false;
  }
  const glm::dvec3 n = glm::cross(v[1] - v[0], v[2] - v[0]);
  const double r = glm::dot(h, glm::abs(n));
  if (std::abs(glm::dot(n, v[0])) > r) return false;
  for (int e = 0; e < 3; ++e) {
    const glm::dvec3 edge = v[size_t((e + 1) % 3)] - v[size_t(e)];
    for (int a = 0; a < 3; ++a) {
      glm::dvec3 unit(0.0);
      unit[a] = 1;
      const glm::dvec3 axis = glm::cross(unit, edge);
      const double p0 = glm::dot(axis, v[0]), p1 = glm::dot(axis, v[1]), p2 = glm::dot(axis, v[2]);
      const double rad = glm::dot(h, glm::abs(axis));
      if (std::min({p0, p1, p2}) > rad || std::max({p0, p1, p2}) < -rad) return false;
    }
  }
  return true;
}

// The same seen from +z, against a column's cell (centre c, half size h): the projected
// triangle's edge normals, so that a long thin triangle across the grid tests only the columns it
// crosses, not its whole bounding rectangle.
bool overlapsCell(const std::array<glm::dvec3, 3>& p, glm::dvec2 c, glm::dvec2 h) {
  for (int e = 0; e < 3; ++e) {
    const glm::dvec2 a(p[size_t(e)]), b(p[size_t((e + 1) % 3)]), o(p[size_t((e + 2) % 3)]);
    const glm::dvec2 axis(a.y - b.y, b.x - a.x);
    const double pa = glm::dot(axis, a - c), po = glm::dot(axis, o - c);
    const double rad = glm::dot(h, glm::abs(axis));
    if (std::min(pa, po) > rad || std::max(pa, po) < -rad) return false;
  }
  return true;
}

struct Overlap {
  uint32_t voxel, mesh, triangle;
  glm::vec3 normal;  // the triangle's, area-weighted
};

// Every (voxel, triangle) pair of the shell, in a deterministic order.
std::vector<Overlap> collectOverlaps(const Grid& g, const std::vector<PreparedMesh>& meshes) {
  const double unit = std::min({g.d.x, g.d.y, g.d.z});
  const glm::dvec3 half = 0.5 * g.d - kBoxShrink * unit;
  tbb::enumerable_thread_specific<std::vector<Overlap>> local;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const std::vector<Triangle>& tris = meshes[m].triangles;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 64), [&](const auto& r) {
      std::vector<Overlap>& out = local.local();
      for (size_t t = r.begin(); t != r.end(); ++t) {
        const glm::dvec3 n = glm::normalize(tris[t].normal);
        std::array<glm::dvec3, 3> p = tris[t].p;
        for (glm::dvec3& c : p) c -= kInwardShift * unit * n;
        const glm::dvec3 tmin = glm::min(p[0], glm::min(p[1], p[2]));
        const glm::dvec3 tmax = glm::max(p[0], glm::max(p[1], p[2]));
        const auto [x0, x1] = g.span(0, tmin.x, tmax.x);
        const auto [y0, y1] = g.span(1, tmin.y, tmax.y);
        // Along z only the voxels the triangle's plane meets over the column (all of the
        // triangle's z range where the plane is near vertical).
        const bool steep = std::abs(n.z) < 1e-6;
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            const glm::dvec2 c(g.centre(0, x), g.centre(1, y));
            if (!overlapsCell(p, c, glm::dvec2(half))) continue;
            double za = tmin.z, zb = tmax.z;
            if (!steep) {
              const double zc = p[0].z - (n.x * (c.x - p[0].x) + n.y * (c.y - p[0].y)) / n.z;
              const double dz =
                  0.5 * (std::abs(n.x) * g.d.x + std::abs(n.y) * g.d.y) / std::abs(n.z);
              za = std::max(za, zc - dz);
              zb = std::min(zb, zc + dz);
              if (za > zb) continue;
            }
            const auto [z0, z1] = g.span(2, za, zb);
            for (int z = z0; z <= z1; ++z) {
              const glm::dvec3 centre(g.centre(0, x), g.centre(1, y), g.centre(2, z));
              if (!overlapsBox({p[0] - centre, p[1] - centre, p[2] - centre}, half)) continue;
              out.push_back({uint32_t(g.index(x, y, z)), uint32_t(m), uint32_t(t),
                             glm::vec3(tris[t].normal)});
            }
          }
      }
    });
  }
  std::vector<Overlap> all;
  for (std::vector<Overlap>& v : local) all.insert(all.end(), v.begin(), v.end());
  tbb::parallel_sort(all.begin(), all.end(), [](const Overlap& a, const Overlap& b) {
    return std::tie(a.voxel, a.mesh, a.triangle) < std::tie(b.voxel, b.mesh, b.triangle);
  });
  return all;
}

uint32_t packSurface(glm::dvec3 n, uint32_t material) {
  const double len = glm::length(n);
  if (len > 0 && std::isfinite(len))
    n /= len;
  else
    n = glm::dvec3(0.0);  // opposite faces cancelled: no direction
  uint32_t out = (material + 1) << 24;
  for (int c = 0; c < 3; ++c)
    out |= uint32_t(std::lround(std::clamp(n[c] * 0.5 + 0.5, 0.0, 1.0) * 255.0)) << (8 * c);
  return out;
}

// The shell: solid, with the mean normal and the material of the mesh with the most area there.
void writeSurface(const std::vector<Overlap>& overlaps, const std::vector<VolumeMesh>& meshes,
                  ObjectVolume& v) {
  for (size_t i = 0; i < overlaps.size();) {
    const uint32_t voxel = overlaps[i].voxel;
    glm::dvec3 sum(0.0);
    double bestArea = -1;
    uint32_t bestMesh = 0;
    while (i < overlaps.size() && overlaps[i].voxel == voxel) {
      const uint32_t mesh = overlaps[i].mesh;
      double area = 0;
      for (; i < overlaps.size() && overlaps[i].voxel == voxel && overlaps[i].mesh == mesh; ++i) {
        sum += glm::dvec3(overlaps[i].normal);
        area += glm::length(glm::dvec3(overlaps[i].normal));
      }
      if (area > bestArea) {
        bestArea = area;
        bestMesh = mesh;
      }
    }
    v.occupancy[voxel] = 255;
    v.surface[voxel] = packSurface(sum, meshes[bestMesh].material);
  }
}

// Shell voxels whose centre lies outside, next to the interior, are the conservative surface's
// excess: half a voxel all round, which rays marched through the volume would see as an object
// grown by that much (a sphere's shadow 5% too dark at 64^3). They become kShell, which the
// marching passes through; shell voxels away from any interior (thin sheets, open meshes) stay
// solid so that such objects still block.
void markOuterShell(const std::vector<uint8_t>& parity, ObjectVolume& v) {
  const glm::ivec3 n = v.size;
  auto index = [&](int x, int y, int z) {
    return (size_t(z) * size_t(n.y) + size_t(y)) * size_t(n.x) + size_t(x);
  };
  for (int z = 0; z < n.z; ++z)
    for (int y = 0; y < n.y; ++y)
      for (int x = 0; x < n.x; ++x) {
        const size_t i = index(x, y, z);
        if (v.surface[i] == 0 || parity[i] == 255) continue;
        const int nb[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z},
                              {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
        for (const auto& q : nb)
          if (q[0] >= 0 && q[1] >= 0 && q[2] >= 0 && q[0] < n.x && q[1] < n.y && q[2] < n.z &&
              parity[index(q[0], q[1], q[2])] == 255) {
            v.occupancy[i] = ObjectVolume::kShell;
            break;
          }
      }
}

}  // namespace
}  // namespace voxelization

ObjectVolume voxelizeSolid(const std::vector<VolumeMesh>& meshes, glm::ivec3 size) {
  voxelization::validate(meshes, size);
  ObjectVolume v;
  v.size = size;
  glm::dvec3 bmin(std::numeric_limits<double>::infinity()), bmax(-bmin);
  const std::vector<voxelization::PreparedMesh> prepared =
      voxelization::prepare(meshes, bmin, bmax, v.skippedTriangles);
  const voxelization::Grid g = voxelization::makeGrid(bmin, bmax, size);
  v.lo = glm::vec3(g.lo);
  v.hi = glm::vec3(g.lo + glm::dvec3(size) * g.d);
  const size_t voxels = size_t(size.x) * size_t(size.y) * size_t(size.z);
  v.occupancy.assign(voxels, 0);
  v.surface.assign(voxels, 0);

  const size_t columns = size_t(size.x) * size_t(size.y);
  for (size_t m = 0; m < prepared.size(); ++m) {
    const uint64_t open = voxelization::fillParity(g, prepared[m], v.occupancy);
    if (open == 0) continue;
    v.warnings.push_back(voxelization::meshName(meshes, m) + " is not closed: " +
                         std::to_string(open) + " of " + std::to_string(columns) +
                         " voxel columns cross it an odd number of times, and only its surface "
                         "is solid there");
  }
  v.parityVoxels = uint64_t(std::count(v.occupancy.begin(), v.occupancy.end(), uint8_t(255)));
  const std::vector<uint8_t> parity = v.occupancy;
  voxelization::writeSurface(voxelization::collectOverlaps(g, prepared), meshes, v);
  voxelization::markOuterShell(parity, v);
  v.solidVoxels = uint64_t(voxels - size_t(std::count(v.occupancy.begin(), v.occupancy.end(), 0)));
  v.boundaryVoxels = uint64_t(voxels - size_t(std::count(v.surface.begin(), v.surface.end(), 0u)));
  return v;
}

}  // namespace nestlight::gi
