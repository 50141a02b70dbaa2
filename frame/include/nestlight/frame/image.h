// The point view's frames: RGBA floats, top row first, display-referred (the scan's recorded sRGB
// colour), or linear (`linear`: an HDR colour layer drawn for an EXR file). Reading and writing
// them as files is the viewer's (nestlight/viewer/image.h), through gi's image library.
#pragma once

#include <cstddef>
#include <vector>

namespace nestlight::frame {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;  // 4 per pixel
  bool linear = false;      // rgb is linear (unbounded), not display-referred
  float* at(int x, int y) { return &rgba[4 * (size_t(y) * width + x)]; }
  const float* at(int x, int y) const { return &rgba[4 * (size_t(y) * width + x)]; }
};

}  // namespace nestlight::frame
