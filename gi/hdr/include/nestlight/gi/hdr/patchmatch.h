// Generalized PatchMatch for HDR expansion (Sabbadin, Palma, Banterle, Boubekeur and Cignoni, "High
// Dynamic Range Point Clouds for Real-Time Relighting", 2019, section 4.1): for every pixel of an
// LDR rendering of the point cloud (the source), the most similar patch of the LDR photograph (the
// target), found with the generalised PatchMatch of Barnes, Shechtman, Goldman and Finkelstein,
// "The Generalized PatchMatch Correspondence Algorithm" (ECCV 2010). A match is a similarity
// transform: centre, rotation angle and scale, so that the photograph may see the scene rotated by
// any angle and at another scale than the rendering. Both images are solved coarse to fine on
// Gaussian pyramids, which is what makes random search find large rotations and scale changes: at
// the coarsest level (about 32 pixels on the short side) a patch covers a good part of the image
// and the whole space of transforms is small. The caller then fetches the HDR photograph's values
// at the matched centres (fetch) and rejects matches whose SSD exceeds a threshold (the paper's
// t_h = 1). The target is sampled at the patch's scale without prefiltering, so near the top of
// the scale range a photograph with detail finer than 2 pixels aliases and matches worse.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "nestlight/gi/hdr_image.h"

namespace nestlight::gi::hdr {

struct PatchMatchOptions {
  int patchRadius = 3;  // (2r+1)^2 patches: 7x7
  int iterations = 5;   // propagation + random search sweeps per pyramid level
  // Pyramid levels including the full resolution; 0: as many as keep the shortest side of either
  // image at 32 pixels or more; 1: single resolution.
  int levels = 0;
  // Scale range searched: the size of the target's patch over the source's (2: the photograph
  // sees the scene twice as large as the rendering). minScale == maxScale fixes the scale.
  float minScale = 0.5f, maxScale = 2.0f;
  bool rotation = true;  // search angles in [-pi, pi); false: angle 0 only
  // Start every pixel from the same place in the target (scaled by the size ratio), not only a
  // random transform: for a source rendered from the target's own camera. Matches that are only
  // as good (the SSD-0 ties of clipped regions) then keep the registered place; better ones
  // still replace it.
  bool identityStart = false;
  // > 0: random search only within this many target pixels of the current match (at full
  // resolution, halved per coarser level), for a source registered with the target that only
  // needs local refinement; 0: the whole target (the algorithm's own search).
  float searchRadius = 0;
  uint64_t seed = 1;  // the same seed gives the same field, whatever the thread count
};

// One entry per SOURCE pixel, top row first. Pixel coordinates put pixel (i, j)'s centre at
// (i, j). The source patch offset d (integer, |d_x|, |d_y| <= r) is compared with the target at
// position + scale * R(angle) * d, R(a) = [[cos a, -sin a], [sin a, cos a]] acting on (x, y) with
// y pointing down (so a positive angle turns clockwise on screen), sampled bilinearly.
struct PatchMatchField {
  int width = 0, height = 0;              // the source's size
  int targetWidth = 0, targetHeight = 0;  // the size of the image positions point into
  std::vector<glm::vec2> position;        // matched centre in the target; (-1, -1) masked out
  std::vector<float> angle;               // radians in [-pi, pi); 0 masked out
  std::vector<float> scale;               // in [minScale, maxScale]; 1 masked out
  // The patch distance at full resolution: the sum over the (2r+1)^2 patch pixels and the 3
  // channels of squared differences of the image values given (display-referred, in [0, 1] for
  // the paper's LDR images: a 7x7 patch sums 147 terms, so t_h = 1 allows an RMS difference of
  // about 0.08 per channel). Within r of the source's border, where part of the patch falls
  // outside the source, the kept terms' sum is scaled up to the full patch's count. +infinity
  // where the source mask excludes the pixel.
  std::vector<float> ssd;

  size_t index(int x, int y) const { return size_t(y) * size_t(width) + size_t(x); }
};

// Matches every source pixel whose mask entry is nonzero (all pixels when sourceMask is null;
// otherwise it holds source.pixels() entries). Masked-out pixels are not matched at full
// resolution (coarser levels match everything, to carry propagation across the mask's holes), but
// their colours still take part in their neighbours' patches. Source patch pixels outside the
// source are left out of the SSD (see ssd); target samples outside the target clamp to its edge,
// and matched centres stay inside it. Non-finite image values count as 0. Throws nestlight::Error
// on an empty image, a mask of the wrong size or bad options.
PatchMatchField generalizedPatchMatch(const HdrImage& source, const HdrImage& target,
                                      const PatchMatchOptions& options = {},
                                      const std::vector<uint8_t>* sourceMask = nullptr);

// The values of `image` (the target's size: e.g. the HDR photograph beside the LDR one matched)
// at the field's positions, bilinear, as an image of the source's size; 0 where the ssd is not
// finite (masked out). Throws nestlight::Error when `image` is not the target's size.
HdrImage fetch(const PatchMatchField& field, const HdrImage& image);

}  // namespace nestlight::gi::hdr
