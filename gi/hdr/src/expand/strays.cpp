// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, after step 3:
// unregistered, matched values far above the median of the matched values around them are stray
// matches and are rejected. Not in the paper; measured below.
#include <algorithm>
#include <cmath>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

void Expansion::rejectStrays() {
  if (!o.photoView && o.maxLocalRatio > 0) {
    // Unregistered, a clipped patch whose unclipped rim resembles a light's glow matches that
    // light (a lamp the scan lacks: its exposed core is as white as the clipped floor) and fetches
    // hundreds of times the clipping, where the clipped region around it fetched a few times it.
    // A clipped surface's radiance is smooth next to its neighbours' matches; a value far above
    // the median of the matched values around it is a stray match, and the in-fill would spread
    // it. Measured with the lamp in the frame but not in the scan: values up to 370 times the
    // clipping beside floor matches of 2 to 4 made the layer 2.66 against the LDR colour's 0.71
    // (0.31 rejected). A light the scan has loses its rim matches the same way and is in-filled.
    const int r = o.localRadius;
    for (size_t vi = 0; vi < renderings.size(); ++vi) {
      Expanded& e = expanded[vi];
      const int w = e.hdr.width, h = e.hdr.height;
      std::vector<float> y(size_t(w) * size_t(h), -1.0f);
      for (size_t i = 0; i < y.size(); ++i)
        if (std::isfinite(e.ssd[i]))
          y[i] = luminance(e.hdr.get(int(i % size_t(w)), int(i / size_t(w))));
      std::vector<float> window;
      for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
          const size_t i = size_t(py) * size_t(w) + size_t(px);
          if (y[i] <= 1.0f) continue;  // within the clipping: nothing expanded
          window.clear();
          for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx) {
              const int qx = px + dx, qy = py + dy;
              if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              if (const float v = y[size_t(qy) * size_t(w) + size_t(qx)]; v >= 0)
                window.push_back(v);
            }
          std::nth_element(window.begin(), window.begin() + std::ptrdiff_t(window.size() / 2),
                           window.end());
          if (y[i] > float(o.maxLocalRatio) * std::max(1.0f, window[window.size() / 2])) {
            e.ssd[i] = INFINITY;
            rep.strayPixels++;
          }
        }
    }
  }
}

}  // namespace nestlight::gi::hdr::expand
