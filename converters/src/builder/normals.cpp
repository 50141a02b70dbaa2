// Closed-form plane-fit normals: Rohmer, Jendersie, Grosch, "Natural Environment Illumination:
// Coherent Interactive Augmented Reality for Mobile and non-Mobile Devices", section 5.
// The k-nearest-neighbour search uses nanoflann (DESIGN.md: 1.3 us per k=16 query on Morton-sorted
// points, against 2.3 us for PCL's FLANN tree).
#include "nestlight/converters/normals.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>

namespace nestlight {

bool fitPlaneNormal(const double* xyz, size_t count, float normal[3]) {
  normal[0] = normal[1] = normal[2] = 0;
  if (count < 3) return false;
  double m[3] = {0, 0, 0};
  for (size_t i = 0; i < count; ++i)
    for (int a = 0; a < 3; ++a) m[a] += xyz[3 * i + a];
  for (int a = 0; a < 3; ++a) m[a] /= static_cast<double>(count);
  // Second moments of the centred points.
  double xx = 0, yy = 0, zz = 0, xy = 0, xz = 0, yz = 0;
  for (size_t i = 0; i < count; ++i) {
    double x = xyz[3 * i] - m[0], y = xyz[3 * i + 1] - m[1], z = xyz[3 * i + 2] - m[2];
    xx += x * x, yy += y * y, zz += z * z, xy += x * y, xz += x * z, yz += y * z;
  }
  // With n_z = 1: [xx xy; xy yy] [nx ny]^T = -[xz yz]^T, and likewise for n_x = 1 and n_y = 1.
  const double detZ = xx * yy - xy * xy;
  const double detY = xx * zz - xz * xz;
  const double detX = yy * zz - yz * yz;
  const double best = std::max({detX, detY, detZ});
  // Relative threshold: the determinant scales with the fourth power of the neighbourhood size.
  const double scale = xx + yy + zz;
  if (!(best > 1e-12 * scale * scale)) return false;
  double n[3];
  if (best == detZ) {
    n[0] = (yz * xy - xz * yy) / detZ;
    n[1] = (xy * xz - xx * yz) / detZ;
    n[2] = 1;
  } else if (best == detY) {
    n[0] = (yz * xz - xy * zz) / detY;
    n[1] = 1;
    n[2] = (xy * xz - xx * yz) / detY;
  } else {
    n[0] = 1;
    n[1] = (xz * yz - xy * zz) / detX;
    n[2] = (xy * yz - xz * yy) / detX;
  }
  double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int a = 0; a < 3; ++a) normal[a] = static_cast<float>(n[a] / len);
  return true;
}

namespace {
struct Cloud {
  const uint32_t* pos;
  size_t n;
  size_t kdtree_get_point_count() const { return n; }
  double kdtree_get_pt(size_t i, size_t dim) const { return pos[3 * i + dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud,
                                                 3, size_t>;

// Moves the points of `xyz` that lie within `limit` of `q` along `n` to its front; returns how
// many.
size_t keepWithinDepth(double* xyz, size_t count, const double q[3], const float n[3],
                       double limit) {
  size_t kept = 0;
  for (size_t j = 0; j < count; ++j) {
    double depth = 0;
    for (int a = 0; a < 3; ++a) depth += (xyz[3 * j + a] - q[a]) * n[a];
    if (std::abs(depth) > limit) continue;
    for (int a = 0; a < 3; ++a) xyz[3 * kept + a] = xyz[3 * j + a];
    ++kept;
  }
  return kept;
}

// Section 5's depth rule on one neighbourhood (`xyz`, nearest first; `normal` holds the fit to all
// of it, and receives the fit to the neighbours kept). The paper drops the samples whose depth
// along the view ray differs by more than the limit from that of the sample nearest the pixel.
// A converted scan has no scanner position, so the reference is the point itself (its own nearest
// sample) and depth is measured along the first fit's normal, the direction a scanner sees the
// surface from at best. Across a discontinuity that fit lies between the two surfaces, yet where
// the point's own surface holds most of the neighbours its normal is near enough to theirs that
// depth along it tells the surfaces apart (tests/converters/normals_test.cpp: a thin wall).
// Where its own surface holds about half of them the first fit can lie anywhere (in the wall's
// plane, even) and the rule cannot help: that needs the scanner's view direction.
void applyDepthRule(double* xyz, size_t count, const double q[3], double limit, float normal[3]) {
  const size_t kept = keepWithinDepth(xyz, count, q, normal, limit);
  if (kept == count) return;  // a smooth surface: nothing dropped
  float refit[3];
  // Fewer than three kept, or all in a line: the first fit stands.
  if (fitPlaneNormal(xyz, kept, refit)) std::copy(refit, refit + 3, normal);
}

}  // namespace

void estimateNormals(const uint32_t* pos, size_t n, unsigned k, int orientation,
                     const double centre[3], float* normals, double depthLimit) {
  if (n == 0) return;
  Cloud cloud{pos, n};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const size_t kk = std::min<size_t>(k, n);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<size_t> idx(kk);
        std::vector<double> dist(kk), xyz(3 * kk);
        for (size_t i = r.begin(); i < r.end(); ++i) {
          double q[3] = {double(pos[3 * i]), double(pos[3 * i + 1]), double(pos[3 * i + 2])};
          size_t found = tree.knnSearch(q, kk, idx.data(), dist.data());
          for (size_t j = 0; j < found; ++j)
            for (int a = 0; a < 3; ++a) xyz[3 * j + a] = pos[3 * idx[j] + a];
          float* nrm = normals + 3 * i;
          if (!fitPlaneNormal(xyz.data(), found, nrm)) continue;
          if (depthLimit > 0) applyDepthRule(xyz.data(), found, q, depthLimit, nrm);
          // A plane fit has no sign. Orient by the scan's shape: statues and buildings seen from
          // outside face away from their centre; interiors face it; terrain faces up.
          double d;
          if (orientation == 2) {
            d = nrm[2];
          } else {
            double v[3] = {q[0] - centre[0], q[1] - centre[1], q[2] - centre[2]};
            d = (v[0] * nrm[0] + v[1] * nrm[1] + v[2] * nrm[2]) * (orientation == 1 ? -1 : 1);
          }
          if (d < 0)
            for (int a = 0; a < 3; ++a) nrm[a] = -nrm[a];
        }
      });
}

}  // namespace nestlight
