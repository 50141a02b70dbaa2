// Cut selection: which nodes the view wants this frame.
#pragma once

#include <cstdint>
#include <vector>

#include "nestlight/streaming/streamer.h"
#include "nestlight/streaming/view.h"
#include "node_table.h"

namespace nestlight::streaming::detail {

struct CutResult {
  std::vector<uint32_t> nodes;  // a node's parent always comes before it
  uint64_t points = 0;
  uint64_t bytes = 0;             // resident bytes, known or estimated
  uint32_t pendingHierarchy = 0;  // cut nodes the view would refine whose children are unknown
  bool budgetBound = false;       // a budget ended the cut before the screen-space error did
};

// The cut is the prefix of a traversal from the root in decreasing projected size of the nodes'
// bounding spheres (ties: NodeKey order) that fits the point and byte budgets (the first node that
// does not fit ends it): visible nodes that are not bad, whose children become candidates when
// the node's spacing projects to more than budgets.spacingPixels. `bytesPerPoint` estimates the
// resident bytes of nodes never prepared. Sets Node::cutFrame, weight and refine.
class CutSelector {
 public:
  void select(NodeTable& table, const View& view, const Budgets& budgets, double bytesPerPoint,
              uint64_t frame, CutResult& out);

 private:
  struct Candidate {
    double weight;    // projected radius of the bounding sphere, pixels
    double distance;  // eye to the bounding sphere, world units (0 inside)
    uint32_t node;
    uint8_t planes;  // frustum planes the node's box is not yet known to lie inside
  };
  bool selectAll(NodeTable& table, const View& view, const Frustum& frustum, const Budgets& budgets,
                 double bytesPerPoint, uint64_t frame, CutResult& out);
  void selectByPriority(NodeTable& table, const View& view, const Frustum& frustum,
                        const Budgets& budgets, double bytesPerPoint, uint64_t frame,
                        CutResult& out);

  std::vector<Candidate> work_;  // the stack or the heap; kept between frames
};

}  // namespace nestlight::streaming::detail
