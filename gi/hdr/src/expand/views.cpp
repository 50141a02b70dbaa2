// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, step 1: the
// views the scan is rendered from (given, or cube maps looking at the over-exposed points, with
// the registered photograph's own camera first), the photograph at the size PatchMatch sees it,
// and the LDR renderings (pass B).
#include <algorithm>
#include <cmath>

#include "expand/expansion.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr::expand {

namespace {

// Box-filters `img` down by an integer factor until its long side is at most `maxSize`.
HdrImage shrink(const HdrImage& img, int maxSize) {
  const int f = std::max(1, (std::max(img.width, img.height) + maxSize - 1) / maxSize);
  if (f == 1) return img;
  HdrImage out(img.width / f, img.height / f);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      glm::dvec3 s(0);
      int n = 0;
      for (int j = 0; j < f; ++j)
        for (int i = 0; i < f; ++i) {
          const Rgb c = img.get(x * f + i, y * f + j);
          if (std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b))
            s += glm::dvec3(c), n++;
        }
      out.set(x, y, n ? Rgb(s / double(n)) : Rgb(0));
    }
  return out;
}

}  // namespace

void Expansion::chooseViews() {
  const Box3d& b = meta.bounds;
  const glm::dvec3 centre{(b.min.x + b.max.x) / 2, (b.min.y + b.max.y) / 2,
                          (b.min.z + b.max.z) / 2};
  const double diagonal =
      glm::length(glm::dvec3(b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z));
  rep.views = o.views.empty() ? automaticViews(sample.positions, sample.normals, centre, diagonal,
                                               o.autoViews, o.faceSize)
                              : o.views;
  // The photograph as PatchMatch sees it (box-filtered down to maxPhotoSize).
  small = shrink(photo, o.maxPhotoSize);
  // The mask at PatchMatch's size: a pixel counts only if every photograph pixel it averages does.
  if (!o.photoMask.empty()) {
    HdrImage m(photo.width, photo.height);
    for (size_t i = 0; i < photo.pixels(); ++i)
      if (o.photoMask[i]) m.rgb[3 * i] = m.rgb[3 * i + 1] = m.rgb[3 * i + 2] = 1.0f;
    const HdrImage shrunk = shrink(m, o.maxPhotoSize);
    smallMask.resize(shrunk.pixels());
    for (size_t i = 0; i < shrunk.pixels(); ++i) smallMask[i] = shrunk.rgb[3 * i] >= 0.999f;
  }
  if (o.photoView) {
    // Rendered at the matched photograph's size, so that its pixels are the photograph's and the
    // identity start is the identity.
    const View& v = *o.photoView;
    const double aspect = double(v.width) / double(v.height),
                 photoAspect = double(photo.width) / double(photo.height);
    if (std::abs(aspect / photoAspect - 1.0) > 0.01)
      throw Error("", "photo view",
                  "is " + std::to_string(v.width) + " x " + std::to_string(v.height) +
                      ", the photograph " + std::to_string(photo.width) + " x " +
                      std::to_string(photo.height) +
                      ": a registered camera has the photograph's aspect");
    View sized =
        lookAt(v.position, v.position + v.forward, v.up, v.fovYDegrees, small.width, small.height);
    sized.name = v.name.empty() ? "photo" : v.name;
    rep.views.insert(rep.views.begin(), sized);
  }
  if (rep.views.empty()) throw Error("", "", "no views to render the scan from");
}

void Expansion::render() {
  const auto t = Clock::now();
  SplatOptions splat;
  splat.progress = [&](uint64_t d, uint64_t n) { progress("render", double(d) / double(n)); };
  renderings = renderViews(scan, rep.views, Payload::Display8, splat);
  rep.seconds["render"] = seconds(t);
}

}  // namespace nestlight::gi::hdr::expand
