// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, step 4:
// back-projection of the matched HDR values onto the over-exposed points (LDR luminance above
// t_l), into the scratch file (pass C); the points no view gives a value are left to the in-fill.
// Then the check that enough of them took a value.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

bool Expansion::projectPoint(const ScanNode& n, size_t i, double y,
                             std::vector<std::pair<glm::dvec3, double>>& candidates, glm::dvec3& c,
                             bool& seen) const {
  const glm::vec3 l = n.ldr[i];
  double weights = 0;
  seen = false;
  candidates.clear();
  for (size_t vi = 0; vi < renderings.size(); ++vi) {
    // The photograph's own view decides alone for the points it matched.
    if (vi == 1 && o.photoView && !candidates.empty()) break;
    const View& v = renderings[vi].view;
    glm::dvec2 px;
    double d;
    if (!v.project(n.world[i], px, d)) continue;
    const int x = int(std::floor(px.x)), yy = int(std::floor(px.y));
    if (x < 0 || yy < 0 || x >= v.width || yy >= v.height) continue;
    const size_t pi = size_t(yy) * size_t(v.width) + size_t(x);
    // Visible when no splat lies clearly in front: splats are a node spacing across.
    if (d > double(renderings[vi].depth(pi)) + 2.0 * n.spacing + 1e-3 * d) continue;
    seen = true;
    const float ssd = expanded[vi].ssd[pi];
    if (!std::isfinite(ssd)) continue;
    const Rgb h = expanded[vi].hdr.get(x, yy);
    glm::dvec3 cand;
    if (o.mode == ExpansionMode::Rgb) {
      cand = glm::dvec3(h);
    } else {
      cand = glm::dvec3(l) * (double(luminance(h)) / y);
    }
    // The quality field weights candidates: low SSD, high weight.
    const double w = 1.0 / (double(ssd) + 1e-3);
    weights += w;
    candidates.push_back({cand, w});
  }
  if (!(weights > 0)) return false;
  // The weighted median (by luminance) of the views' candidates, where the paper takes the
  // weighted mean. Inside a clipped region every white patch of the photograph matches
  // with SSD 0, so one view may fetch the lamp's values for a sunlit floor; the mean keeps
  // a share of that outlier, the median drops it. Measured on the ground-truth protocol
  // (300k points, 2 cube maps): cloud RMS on the clipped sunlit floor 134 -> 56, on the
  // window wall 151 -> 5.7 (docs/HDR.md).
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return luminance(Rgb(a.first)) < luminance(Rgb(b.first));
  });
  c = candidates.back().first;
  double below = 0;
  for (const auto& [cand, w] : candidates)
    if ((below += w) >= 0.5 * weights) {
      c = cand;
      break;
    }
  return true;
}

void Expansion::backProject() {
  const auto t = Clock::now();
  const fs::path scratchPath =
      (o.scratchDir.empty() ? dir : o.scratchDir) / (o.layerName + ".expand.scratch");
  scratch = std::make_unique<Scratch>(scratchPath, rep.points);
  std::atomic<uint64_t> projected{0}, unseen{0}, rejected{0}, targetCount{0};
  std::atomic<uint64_t> nodesDone{0};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints == 0) return;
    const ScanNode n = scan.read(key, entry);
    std::vector<ScratchRecord> out(n.world.size());
    std::vector<std::pair<glm::dvec3, double>> candidates;
    uint64_t p = 0, u = 0, r = 0;
    for (size_t i = 0; i < n.world.size(); ++i) {
      const glm::vec3 l = n.ldr[i];
      ScratchRecord& rec = out[i];
      rec.rgb[0] = l.r, rec.rgb[1] = l.g, rec.rgb[2] = l.b;
      rec.state = kKept;
      const double y = luminance(l);
      if (!(y > o.overexposed)) continue;
      glm::dvec3 c;
      bool seen;
      if (projectPoint(n, i, y, candidates, c, seen)) {
        rec.rgb[0] = float(c.x), rec.rgb[1] = float(c.y), rec.rgb[2] = float(c.z);
        rec.state = kProjected;
        p++;
      } else {
        rec.state = kTarget;
        (seen ? r : u)++;
      }
    }
    scratch->write(base[ni], out);
    projected += p, unseen += u, rejected += r, targetCount += u + r;
    progress("back-projection", double(++nodesDone) / double(nodes.size()));
  });
  rep.projected = projected, rep.unseen = unseen, rep.rejectedMatches = rejected;
  targets = targetCount;
  checkMatchedShare();
  renderings.clear();
  expanded.clear();
  rep.seconds["back_projection"] = seconds(t);
}

void Expansion::checkMatchedShare() {
  if (rep.overexposed > 0) {
    // Few matched points and many to in-fill: the in-fill would carry a handful of values (right
    // or wrong) over the whole clipped range.
    checks.matchedShare = double(rep.projected) / double(rep.overexposed);
    if (checks.matchedShare < o.minMatchedShare) {
      char buf[400];
      std::snprintf(
          buf, sizeof buf,
          "only %.1f%% of the over-exposed points (%llu of %llu) took a value from the photograph "
          "(at least %.1f%%): the rest would be in-filled from them",
          100 * checks.matchedShare, (unsigned long long)rep.projected,
          (unsigned long long)rep.overexposed, 100 * o.minMatchedShare);
      stopOnFailures({buf});
    }
  }
}

}  // namespace nestlight::gi::hdr::expand
