// Cut selection after Potree's point-budget traversal (Schütz 2016, "Potree: Rendering Large
// Point Clouds in Web Browsers", section 3.3; kept by Potree 2, Schütz, Ohrhallinger, Wimmer 2020):
// a priority queue ordered by the projected size of each node's bounding sphere hands out the
// point budget to the nodes that cover most of the screen first, so the budget buys the most
// visible detail and any prefix of the traversal is a valid cut (a node follows its parent).
// Refinement stops at a screen-space error target, the node's point spacing in pixels, as in
// Potree's minimum node size. The budget on resident bytes is a second budget of the same
// prefix, so that everything the cut wants fits in GPU memory at once and the cut can be drawn
// complete.
//
// When no budget binds, the prefix is the whole traversal and its order does not matter: a
// depth-first walk over the children arrays finds the same set without the priority queue, whose
// pops miss the cache on every node (most frames of a viewer at rest, and the 10k-node case, take
// this path). It gives up, and the priority traversal runs, as soon as the sums exceed a budget.
#include "cut_selection.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "box_cull.h"

namespace nestlight::streaming::detail {

namespace {
struct Weighed {
  double weight, distance;
};
inline Weighed weigh(const Node& n, const View& view) {
  const double dx = n.center[0] - view.eye.x, dy = n.center[1] - view.eye.y,
               dz = n.center[2] - view.eye.z;
  const double d = std::max(std::sqrt(dx * dx + dy * dy + dz * dz) - n.radius, 0.0);
  return {view.projectedPixels(n.radius, d), d};
}
// False when the view's clipping volumes remove the node's cube whole (and so its subtree).
inline bool clipKeeps(const Node& n, const View& view) {
  if (!view.clip || view.clip->empty()) return true;
  Box3d cube;
  cube.min = {n.center[0] - n.half[0], n.center[1] - n.half[1], n.center[2] - n.half[2]};
  cube.max = {n.center[0] + n.half[0], n.center[1] + n.half[1], n.center[2] + n.half[2]};
  return view.clip->keeps(cube) != Overlap::None;
}
inline void clearCut(CutResult& out) {
  out.nodes.clear();
  out.points = out.bytes = 0;
  out.pendingHierarchy = 0;
  out.budgetBound = false;
}
// Takes node `idx` into the cut; true when its children are to be considered next.
inline bool admit(Node& n, uint32_t idx, const Weighed& w, const View& view, const Budgets& budgets,
                  uint64_t frame, CutResult& out) {
  n.cutFrame = frame;
  n.weight = w.weight;
  n.refine =
      n.childMask != 0 && view.projectedPixels(n.spacing, w.distance) > budgets.spacingPixels;
  out.nodes.push_back(idx);
  if (!n.refine) return false;
  if (n.firstChild == kNone) {
    ++out.pendingHierarchy;
    return false;
  }
  return true;
}
inline uint64_t bytesOf(const Node& n, double bytesPerPoint) {
  return n.bytesKnown ? n.bytes : static_cast<uint64_t>(std::ceil(n.numPoints * bytesPerPoint));
}
}  // namespace

void CutSelector::select(NodeTable& table, const View& view, const Budgets& budgets,
                         double bytesPerPoint, uint64_t frame, CutResult& out) {
  const Frustum frustum(view.clipFromWorld);
  if (table.size() == 0) {
    clearCut(out);
    return;
  }
  if (selectAll(table, view, frustum, budgets, bytesPerPoint, frame, out)) return;
  selectByPriority(table, view, frustum, budgets, bytesPerPoint, frame, out);
}

bool CutSelector::selectAll(NodeTable& table, const View& view, const Frustum& frustum,
                            const Budgets& budgets, double bytesPerPoint, uint64_t frame,
                            CutResult& out) {
  clearCut(out);
  work_.clear();
  work_.push_back({0, 0, 0, kAllPlanes});
  while (!work_.empty()) {
    const Candidate c = work_.back();
    work_.pop_back();
    Node& n = table[c.node];
    if (n.residency == Residency::Bad) continue;  // and its subtree: it can never be drawn
    uint8_t planes = c.planes;
    if (planes && !boxInFrustum(frustum, n.center, n.half, planes)) continue;
    if (!clipKeeps(n, view)) continue;
    out.points += n.numPoints;
    out.bytes += bytesOf(n, bytesPerPoint);
    if (out.points > budgets.points || out.bytes > budgets.gpuBytes) {
      // Only the priority traversal's nodes are this frame's cut.
      for (uint32_t idx : out.nodes) table[idx].cutFrame = frame - 1;
      return false;
    }
    if (!admit(n, c.node, weigh(n, view), view, budgets, frame, out)) continue;
    for (uint32_t k = uint32_t(std::popcount(n.childMask)); k-- > 0;)
      work_.push_back({0, 0, n.firstChild + k, planes});
  }
  return true;
}

void CutSelector::selectByPriority(NodeTable& table, const View& view, const Frustum& frustum,
                                   const Budgets& budgets, double bytesPerPoint, uint64_t frame,
                                   CutResult& out) {
  clearCut(out);
  work_.clear();
  // Lower priority: smaller on screen, then later in breadth-first order (deterministic ties).
  auto lower = [&table](const Candidate& a, const Candidate& b) {
    if (a.weight != b.weight) return a.weight < b.weight;
    return table[b.node].key < table[a.node].key;
  };
  auto consider = [&](uint32_t idx, uint8_t planes) {
    const Node& n = table[idx];
    if (planes && !boxInFrustum(frustum, n.center, n.half, planes)) return;
    if (!clipKeeps(n, view)) return;
    const Weighed w = weigh(n, view);
    work_.push_back({w.weight, w.distance, idx, planes});
    std::push_heap(work_.begin(), work_.end(), lower);
  };
  consider(0, kAllPlanes);
  while (!work_.empty()) {
    std::pop_heap(work_.begin(), work_.end(), lower);
    const Candidate c = work_.back();
    work_.pop_back();
    Node& n = table[c.node];
    if (n.residency == Residency::Bad) continue;
    const uint64_t bytes = bytesOf(n, bytesPerPoint);
    if (out.points + n.numPoints > budgets.points || out.bytes + bytes > budgets.gpuBytes) {
      out.budgetBound = true;
      break;
    }
    out.points += n.numPoints;
    out.bytes += bytes;
    if (!admit(n, c.node, {c.weight, c.distance}, view, budgets, frame, out)) continue;
    const uint32_t children = uint32_t(std::popcount(n.childMask));
    for (uint32_t k = 0; k < children; ++k) consider(n.firstChild + k, c.planes);
  }
}

}  // namespace nestlight::streaming::detail
