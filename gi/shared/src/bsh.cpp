#include "nestlight/gi/shared/bsh.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gi/shared/morton.h"
#include "nestlight/gi/shared/normal_cone.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace {

// What a node knows of the points below it.
struct Aggregate {
  glm::dvec3 centre{0};
  double radius = 0;
  NormalCone cone;
  double count = 0;  // points
  glm::dvec3 sumColour{0}, sumColour2{0};
  glm::dvec3 sumNormal{0};  // of the points' unit normals
  glm::dvec3 sumPosition{0};
  double withNormal = 0;  // points that have one
};

// A child of a Karras inner node: a leaf (Morton cell) or another inner node.
struct Ref {
  bool leaf = true;
  uint32_t index = 0;
};

struct InnerNode {
  Ref left, right;
};

// The smallest sphere containing both children's spheres (exact for two spheres). Bottom-up it
// grows beyond the points' own smallest enclosing sphere (on a converted scan's nodes the root
// is 1.13 times the node cube's half diagonal on average, 1.8 at worst); a sphere about the
// points' bounding-box centre containing both children was tried and was never smaller there.
void enclose(const Aggregate& a, const Aggregate& b, glm::dvec3& centre, double& radius) {
  const glm::dvec3 d = b.centre - a.centre;
  const double dist = glm::length(d);
  if (dist + b.radius <= a.radius) {
    centre = a.centre, radius = a.radius;
  } else if (dist + a.radius <= b.radius) {
    centre = b.centre, radius = b.radius;
  } else {
    radius = 0.5 * (dist + a.radius + b.radius);
    centre = a.centre + d * ((radius - a.radius) / dist);
  }
}

class Builder {
 public:
  Builder(const BshPoints& pts, const BshOptions& opt) : pts_(pts), opt_(opt) {}

  Bsh build() {
    Bsh out;
    BshStats& st = out.stats;
    const size_t n = pts_.position.size();
    NL_CHECK(pts_.colour.size() == n);
    NL_CHECK(pts_.normal.empty() || pts_.normal.size() == n);
    NL_CHECK(pts_.radius.empty() || pts_.radius.size() == n);
    NL_CHECK(std::isfinite(opt_.leafRadius) && opt_.leafRadius >= 0);
    st.input = n;
    if (opt_.recordLeaves) out.leafOf.assign(n, BSH_LEAF);

    std::vector<uint32_t> valid;
    valid.reserve(n);
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = 0; i < n; ++i) {
      const glm::vec3 &p = pts_.position[i], &c = pts_.colour[i];
      const bool ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) &&
                      std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b) && c.r >= 0 &&
                      c.g >= 0 && c.b >= 0;
      if (!ok) {
        st.rejected++;
        continue;
      }
      valid.push_back(uint32_t(i));
      lo = glm::min(lo, glm::dvec3(p));
      hi = glm::max(hi, glm::dvec3(p));
    }
    if (valid.empty()) return out;

    // Morton codes over the bounding cube (cubic cells keep the grid isotropic).
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    const double toGrid = extent > 0 ? double(kMortonAxisMax) / extent : 0.0;
    std::vector<uint64_t> codes(valid.size());
    for (size_t k = 0; k < valid.size(); ++k) {
      const glm::dvec3 q = (glm::dvec3(pts_.position[valid[k]]) - lo) * toGrid;
      auto axis = [](double v) { return uint32_t(std::clamp(v, 0.0, double(kMortonAxisMax))); };
      codes[k] = mortonCode(axis(q.x), axis(q.y), axis(q.z));
    }
    radixSortPairs(codes, valid);

    // Cells: runs of equal codes, averaged.
    std::vector<uint64_t> cellCode;
    for (size_t k = 0; k < valid.size();) {
      size_t e = k + 1;
      while (e < valid.size() && codes[e] == codes[k]) ++e;
      Aggregate a;
      for (size_t j = k; j < e; ++j) {
        const uint32_t i = valid[j];
        const glm::dvec3 c(pts_.colour[i]);
        a.centre += glm::dvec3(pts_.position[i]);
        a.sumColour += c;
        a.sumColour2 += c * c;
        const NormalCone nc =
            pts_.normal.empty() ? NormalCone::everything() : NormalCone::of(pts_.normal[i]);
        a.cone = j == k ? nc : merge(a.cone, nc);
        if (!nc.boundsNothing()) {
          a.sumNormal += glm::dvec3(nc.axis);
          a.withNormal += 1;
        }
      }
      a.count = double(e - k);
      a.sumPosition = a.centre;
      a.centre /= a.count;
      // The sphere holds every point's disc.
      a.radius = 0;
      for (size_t j = k; j < e; ++j) {
        const uint32_t i = valid[j];
        const double disc = pts_.radius.empty() ? double(opt_.leafRadius) : double(pts_.radius[i]);
        NL_CHECK(disc >= 0);
        a.radius = std::max(a.radius, disc + glm::length(glm::dvec3(pts_.position[i]) - a.centre));
      }
      if (e - k > 1) st.sharedCells += e - k;
      cellCode.push_back(codes[k]);
      cellFirst_.push_back(uint32_t(k));
      cells_.push_back(a);
      k = e;
    }
    codes.clear();
    const size_t m = cells_.size();
    cellFirst_.push_back(uint32_t(valid.size()));
    if (opt_.recordLeaves) sorted_ = &valid;
    st.leaves = m;
    st.nodesBeforePruning = 2 * m - 1;

    Ref root{true, 0};
    if (m > 1) {
      buildInner(cellCode);
      root = Ref{false, 0};
      inner_.resize(m - 1);
      fill(root);
    }
    out.nodes.reserve(2 * m - 1);
    emit(root, 0, out);
    st.nodes = out.nodes.size();
    st.clusters = clusters_;
    st.depth = depth_;
    return out;
  }

  // The top tree over resident nodes' roots: leaves are the roots (links.y: their index), no
  // voxelisation (distinct nodes stay distinct leaves) and no pruning.
  Bsh buildTop(const std::vector<BshNode>& roots) {
    Bsh out;
    const size_t n = roots.size();
    out.stats.input = n;
    if (n == 0) return out;
    NL_CHECK_MSG(n < (1u << 22), "a top tree over more than 4M nodes");
    top_ = true;
    topRoots_ = &roots;
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (const auto& r : roots)
      lo = glm::min(lo, glm::vec3(r.sphere)), hi = glm::max(hi, glm::vec3(r.sphere));
    const float extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    const float toGrid = extent > 0 ? 16383.0f / extent : 0.0f;
    std::vector<uint64_t> codes(n);
    std::vector<uint32_t> order(n);
    for (uint32_t i = 0; i < n; ++i) {
      const glm::vec3 q =
          glm::clamp((glm::vec3(roots[i].sphere) - lo) * toGrid, glm::vec3(0), glm::vec3(16383));
      // 14 bits per axis, then the index: unique codes even for nodes with one centre.
      codes[i] = mortonCode(uint32_t(q.x), uint32_t(q.y), uint32_t(q.z)) << 22 | i;
      order[i] = i;
    }
    radixSortPairs(codes, order);
    for (uint32_t k = 0; k < n; ++k) {
      const BshNode& r = roots[order[k]];
      Aggregate a;
      a.centre = glm::dvec3(glm::vec3(r.sphere));
      a.radius = r.sphere.w;
      a.count = std::max(double(r.links.z), 1.0);
      a.sumColour = glm::dvec3(glm::vec3(r.colour)) * a.count;
      a.sumColour2 = glm::dvec3(glm::vec3(r.colour)) * glm::dvec3(glm::vec3(r.colour)) * a.count;
      a.cone = r.links.w ? NormalCone{coneAxis(r), r.colour.w} : NormalCone::everything();
      cells_.push_back(a);
      payload_.push_back(order[k]);
    }
    out.stats.leaves = n;
    out.stats.nodesBeforePruning = 2 * n - 1;
    Ref root{true, 0};
    if (n > 1) {
      buildInner(codes);
      root = Ref{false, 0};
      inner_.resize(n - 1);
      fill(root);
    }
    out.nodes.reserve(2 * n - 1);
    emit(root, 0, out);
    out.stats.nodes = out.nodes.size();
    out.stats.depth = depth_;
    return out;
  }

 private:
  // Karras 2012: inner node i covers a range of sorted unique codes with i at one end and splits
  // it where the highest differing bit changes; every node's range is found independently.
  void buildInner(const std::vector<uint64_t>& code) {
    const int64_t m = int64_t(code.size());
    innerLinks_.resize(size_t(m - 1));
    auto delta = [&](int64_t i, int64_t j) -> int {
      if (j < 0 || j >= m) return -1;
      return std::countl_zero(code[size_t(i)] ^ code[size_t(j)]);  // codes are unique: < 64
    };
    for (int64_t i = 0; i < m - 1; ++i) {
      const int d = delta(i, i + 1) - delta(i, i - 1) > 0 ? 1 : -1;
      const int dmin = delta(i, i - d);
      int64_t lmax = 2;
      while (delta(i, i + lmax * d) > dmin) lmax *= 2;
      int64_t l = 0;
      for (int64_t t = lmax / 2; t >= 1; t /= 2)
        if (delta(i, i + (l + t) * d) > dmin) l += t;
      const int64_t j = i + l * d;
      const int dnode = delta(i, j);
      int64_t s = 0, t = l;
      do {
        t = (t + 1) / 2;
        if (delta(i, i + (s + t) * d) > dnode) s += t;
      } while (t > 1);
      const int64_t gamma = i + s * d + std::min(d, 0);
      InnerNode& node = innerLinks_[size_t(i)];
      node.left = Ref{std::min(i, j) == gamma, uint32_t(gamma)};
      node.right = Ref{std::max(i, j) == gamma + 1, uint32_t(gamma + 1)};
    }
  }

  Aggregate& agg(const Ref& r) { return r.leaf ? cells_[r.index] : inner_[r.index]; }

  // Bottom-up; recursion depth is bounded by the code length (each level's common prefix is
  // longer than its parent's).
  void fill(const Ref& r) {
    if (r.leaf) return;
    const InnerNode& node = innerLinks_[r.index];
    fill(node.left);
    fill(node.right);
    const Aggregate &a = agg(node.left), &b = agg(node.right);
    Aggregate& p = inner_[r.index];
    enclose(a, b, p.centre, p.radius);
    p.cone = merge(a.cone, b.cone);
    p.count = a.count + b.count;
    p.sumColour = a.sumColour + b.sumColour;
    p.sumPosition = a.sumPosition + b.sumPosition;
    p.sumColour2 = a.sumColour2 + b.sumColour2;
    p.sumNormal = a.sumNormal + b.sumNormal;
    p.withNormal = a.withNormal + b.withNormal;
  }

  bool similar(const Aggregate& a) const {
    const glm::dvec3 mean = a.sumColour / a.count;
    const glm::dvec3 var = glm::max(a.sumColour2 / a.count - mean * mean, glm::dvec3(0));
    if (std::max({var.r, var.g, var.b}) >= double(opt_.colourVariance)) return false;
    // Without normals (a scan that has none) discs face each receiver and only colour counts; a
    // mix of known and unknown normals is never merged.
    if (a.withNormal == 0) return true;
    if (a.withNormal < a.count) return false;
    return glm::length(a.sumNormal) / a.count > double(opt_.normalAgreement);
  }

  uint32_t emit(const Ref& r, int depth, Bsh& out) {
    depth_ = std::max(depth_, depth);
    const Aggregate& a = agg(r);
    const uint32_t index = uint32_t(out.nodes.size());
    out.nodes.push_back(pack(a));
    const bool collapse = !top_ && !r.leaf && opt_.prune && similar(a);
    if (r.leaf && top_) {
      out.nodes[index].links.x = BSH_LEAF;
      out.nodes[index].links.y = payload_[r.index];
      // The sphere and cone exactly as the node's own root stores them.
      const BshNode& root = (*topRoots_)[payload_[r.index]];
      out.nodes[index].sphere = root.sphere;
      out.nodes[index].colour.w = root.colour.w;
      out.nodes[index].links.w = root.links.w;
      return index;
    }
    if (r.leaf || collapse) {
      clusters_ += collapse;
      // A Karras node covers a contiguous range of cells: from its leftmost to its rightmost.
      Ref first = r, last = r;
      while (!first.leaf) first = innerLinks_[first.index].left;
      while (!last.leaf) last = innerLinks_[last.index].right;
      if (sorted_)
        for (uint32_t k = cellFirst_[first.index]; k < cellFirst_[last.index + 1]; ++k)
          out.leafOf[(*sorted_)[k]] = index;
      BshNode& n = out.nodes[index];
      float disc = float(a.radius);
      if (collapse) {
        // A cluster is drawn as one disc in its mean plane, about its centroid (the bounding
        // sphere's centre can lie off the surface), wide enough to cover every cell. (A disc of
        // the area its cells stand for left half a closed sphere's micro-buffers uncovered:
        // coarse levels' points stand for more than their spacing squared.)
        const glm::dvec3 centroid = a.sumPosition / a.count;
        double reach = 0;
        for (uint32_t c = first.index; c <= last.index; ++c)
          reach = std::max(reach, glm::length(cells_[c].centre - centroid) + cells_[c].radius);
        const double mag =
            std::max({std::fabs(centroid.x), std::fabs(centroid.y), std::fabs(centroid.z), reach});
        n.sphere = glm::vec4(glm::vec3(centroid), float(reach + 8.0 * mag * 1.2e-7));
        disc = float(reach);
      }
      n.links.x = BSH_LEAF;
      n.links.y = std::bit_cast<uint32_t>(disc);
      return index;
    }
    const InnerNode& node = innerLinks_[r.index];
    const uint32_t left = emit(node.left, depth + 1, out);
    const uint32_t right = emit(node.right, depth + 1, out);
    NL_CHECK(left == index + 1);
    BshNode& p = out.nodes[index];
    p.links.x = left;
    p.links.y = right;
    // The stored (float, quantised) children must lie inside the stored parent, as traversals
    // test them: widen the parent by whatever rounding took from it.
    for (uint32_t k : {left, right}) {
      const BshNode& c = out.nodes[k];
      const float reach = glm::length(glm::vec3(c.sphere) - glm::vec3(p.sphere)) + c.sphere.w;
      if (reach > p.sphere.w) p.sphere.w = std::nextafter(reach, INFINITY);
      if (p.links.w == 0) continue;
      if (c.links.w == 0) {
        p.links.w = 0;
        p.colour.w = float(BSH_CONE_NONE);
        continue;
      }
      const glm::vec3 pa = frame::unpackNormal(p.links.w), ca = frame::unpackNormal(c.links.w);
      const float need =
          std::atan2(glm::length(glm::cross(pa, ca)), glm::dot(pa, ca)) + c.colour.w + 1e-6f;
      if (need >= float(BSH_CONE_NONE)) {
        p.links.w = 0;
        p.colour.w = float(BSH_CONE_NONE);
      } else {
        p.colour.w = std::max(p.colour.w, need);
      }
    }
    return index;
  }

  static BshNode pack(const Aggregate& a) {
    BshNode n{};
    const glm::vec3 c(a.centre);
    // Float rounding of the centre and radius must not let a child's sphere poke out of its
    // parent's: widen by a few ulps of the coordinates' magnitude.
    const double mag =
        std::max({std::fabs(a.centre.x), std::fabs(a.centre.y), std::fabs(a.centre.z), a.radius});
    n.sphere = glm::vec4(c, float(a.radius + 8.0 * mag * 1.2e-7));
    n.colour = glm::vec4(glm::vec3(a.sumColour / a.count), 0.0f);
    if (a.cone.boundsNothing()) {
      n.colour.w = float(BSH_CONE_NONE);
      n.links.w = 0;
    } else {
      // The axis is stored in 2 x 16 bits: widen the aperture by what that quantisation turned
      // it, and by float rounding of the merges (1e-5 rad), so the cone still contains its normals
      // (emit() then widens parents to contain their children's stored cones).
      const uint32_t word = frame::packNormal(a.cone.axis.x, a.cone.axis.y, a.cone.axis.z);
      const glm::vec3 back = frame::unpackNormal(word);
      const float err =
          std::atan2(glm::length(glm::cross(back, a.cone.axis)), glm::dot(back, a.cone.axis));
      const float half = a.cone.halfAngle + err + 1e-5f;
      if (word == 0 || half >= float(BSH_CONE_NONE)) {
        n.colour.w = float(BSH_CONE_NONE);
        n.links.w = 0;
      } else {
        n.colour.w = half;
        n.links.w = word;
      }
    }
    n.links.z = uint32_t(std::min(a.count, 4294967295.0));
    return n;
  }

  const BshPoints& pts_;
  const BshOptions& opt_;
  std::vector<Aggregate> cells_, inner_;
  std::vector<InnerNode> innerLinks_;
  std::vector<uint32_t> cellFirst_;  // per cell, its first point in sorted order; + end
  const std::vector<uint32_t>* sorted_ =
      nullptr;  // the valid points in Morton order (recordLeaves)
  uint64_t clusters_ = 0;
  int depth_ = 0;
  bool top_ = false;
  std::vector<uint32_t> payload_;  // top tree: per leaf, the root it stands for
  const std::vector<BshNode>* topRoots_ = nullptr;
};

}  // namespace

Bsh buildBsh(const BshPoints& points, const BshOptions& options) {
  return Builder(points, options).build();
}

Bsh buildTopTree(const std::vector<BshNode>& roots) {
  const BshPoints none;
  const BshOptions opt;
  return Builder(none, opt).buildTop(roots);
}

glm::vec3 coneAxis(const BshNode& n) {
  return n.links.w ? frame::unpackNormal(n.links.w) : glm::vec3(0);
}

}  // namespace nestlight::gi
