// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, step 3:
// generalised PatchMatch of each rendering against the exposed photograph, and the HDR mapping
// (the photograph's values at the matches, times the exposure). Matches above t_h are rejected,
// and so are those the paper keeps but we measured to mislead: blind patches (over-exposed in
// every pixel) and, registered or masked, matches that land on what the scan lacks.
#include <algorithm>
#include <cmath>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

namespace {

// 1 where every covered pixel of the (2r+1)^2 patch around a covered pixel is over-exposed
// (linear LDR luminance above t_l): a summed-area table of the pixels that are not.
std::vector<uint8_t> blindPatches(const HdrImage& ldr, const std::vector<uint8_t>& covered, int r,
                                  double overexposed) {
  const int w = ldr.width, h = ldr.height;
  std::vector<uint32_t> sat(size_t(w + 1) * size_t(h + 1), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      const Rgb c = ldr.get(x, y);
      const bool informative =
          covered[i] && !(luminance(Rgb(linearFromDisplay(c.r), linearFromDisplay(c.g),
                                        linearFromDisplay(c.b))) > overexposed);
      sat[size_t(y + 1) * size_t(w + 1) + size_t(x + 1)] =
          uint32_t(informative) + sat[size_t(y) * size_t(w + 1) + size_t(x + 1)] +
          sat[size_t(y + 1) * size_t(w + 1) + size_t(x)] -
          sat[size_t(y) * size_t(w + 1) + size_t(x)];
    }
  std::vector<uint8_t> out(ldr.pixels(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - r), x1 = std::min(w, x + r + 1), y0 = std::max(0, y - r),
                y1 = std::min(h, y + r + 1);
      const uint32_t n = sat[size_t(y1) * size_t(w + 1) + size_t(x1)] -
                         sat[size_t(y0) * size_t(w + 1) + size_t(x1)] -
                         sat[size_t(y1) * size_t(w + 1) + size_t(x0)] +
                         sat[size_t(y0) * size_t(w + 1) + size_t(x0)];
      out[size_t(y) * size_t(w) + size_t(x)] = covered[size_t(y) * size_t(w) + size_t(x)] && n == 0;
    }
  return out;
}

}  // namespace

void Expansion::preparePhotoCoverage() {
  photoCoverage = o.photoView ? renderings[0].coverage() : std::vector<uint8_t>();
  if (!smallMask.empty()) {
    if (photoCoverage.empty()) {
      photoCoverage = smallMask;
    } else {
      for (size_t i = 0; i < photoCoverage.size(); ++i) photoCoverage[i] &= smallMask[i];
    }
  }
}

bool Expansion::explainedTarget(glm::vec2 p) const {
  // The fetch is bilinear: every pixel of its 2 x 2 footprint must be the scan's.
  const int x0 = std::clamp(int(std::floor(p.x)), 0, small.width - 1),
            y0 = std::clamp(int(std::floor(p.y)), 0, small.height - 1);
  const int x1 = std::min(x0 + 1, small.width - 1), y1 = std::min(y0 + 1, small.height - 1);
  auto at = [&](int x, int y) {
    return photoCoverage[size_t(y) * size_t(small.width) + size_t(x)] != 0;
  };
  return at(x0, y0) && at(x1, y0) && at(x0, y1) && at(x1, y1);
}

void Expansion::match(float exposure) {
  rep.coveredPixels = rep.matchedPixels = rep.blindPixels = rep.backgroundPixels = 0;
  matchScanY.clear();
  matchPhotoY.clear();
  for (size_t i = 0; i < small.rgb.size(); ++i)
    exposedDisplay.rgb[i] = displayFromLinear(std::clamp(exposure * small.rgb[i], 0.0f, 1.0f));
  // Masked-out pixels far outside the display range: a patch touching one costs more than any
  // threshold, so PatchMatch looks for the region's match elsewhere instead of finding it there
  // and having it rejected afterwards.
  for (size_t i = 0; i < smallMask.size(); ++i)
    if (!smallMask[i])
      exposedDisplay.rgb[3 * i] = exposedDisplay.rgb[3 * i + 1] = exposedDisplay.rgb[3 * i + 2] =
          kMaskedOut;
  for (size_t vi = 0; vi < renderings.size(); ++vi) {
    matchView(vi, exposure);
    progress("patchmatch", double(vi + 1) / double(renderings.size()));
  }
}

void Expansion::matchView(size_t vi, float exposure) {
  const HdrImage ldr = renderings[vi].image();
  const std::vector<uint8_t> mask = renderings[vi].coverage();
  PatchMatchOptions pm;
  pm.patchRadius = o.patchRadius;
  pm.iterations = o.patchIterations;
  pm.seed = 1 + vi;
  pm.identityStart = o.photoView && vi == 0;
  if (pm.identityStart) {
    // Registered: rendered at the photograph's size from its camera, so no rotation or scale,
    // and matches only move locally (misregistration, the renderings' splats).
    pm.rotation = false;
    pm.minScale = pm.maxScale = 1.0f;
    pm.searchRadius = float(o.photoSearchRadius);  // 0: anywhere
  }
  const PatchMatchField field = generalizedPatchMatch(ldr, exposedDisplay, pm, &mask);
  Expanded& e = expanded[vi];
  e.hdr = fetch(field, small);
  for (float& v : e.hdr.rgb) v = std::isfinite(v) ? std::max(0.0f, v * exposure) : 0.0f;
  e.ssd = field.ssd;
  const std::vector<uint8_t> blind = pm.identityStart || !o.rejectBlindPatches
                                         ? std::vector<uint8_t>()
                                         : blindPatches(ldr, mask, o.patchRadius, o.overexposed);
  for (size_t i = 0; i < e.ssd.size(); ++i) {
    if (!mask[i]) {
      e.ssd[i] = INFINITY;
      continue;
    }
    if (!blind.empty() && blind[i]) {
      rep.blindPixels++;
      e.ssd[i] = INFINITY;
      continue;
    }
    if (!photoCoverage.empty() && e.ssd[i] <= o.maxSsd && !explainedTarget(field.position[i])) {
      rep.backgroundPixels++;
      e.ssd[i] = INFINITY;
      continue;
    }
    rep.coveredPixels++;
    if (e.ssd[i] <= o.maxSsd) {
      rep.matchedPixels++;
      if (!o.photoView) {
        const int x = int(i % size_t(ldr.width)), y = int(i / size_t(ldr.width));
        matchScanY.push_back(linearLuminance(ldr.get(x, y)));
        matchPhotoY.push_back(luminance(e.hdr.get(x, y)) / exposure);
      }
    } else {
      e.ssd[i] = INFINITY;
    }
  }
  if (!o.debugDir.empty()) {
    fs::create_directories(o.debugDir);
    const std::string stem = (o.debugDir / rep.views[vi].name).string();
    writeExr(stem + "-ldr.exr", ldr);
    writeExr(stem + "-hdr.exr", e.hdr);
  }
}

}  // namespace nestlight::gi::hdr::expand
