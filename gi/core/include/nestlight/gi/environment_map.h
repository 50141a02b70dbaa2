// HDR environment maps in latitude-longitude layout, and their importance sampling (Kronander
// et al., paper 001, section on tabulated CDF sampling; pbrt-v4 section 12.5.3).
//
// Convention (world up is +z, as in the scans): column u in [0,1) is the azimuth
// phi = 2 pi u measured from +x towards +y, row v in [0,1] is the polar angle theta = pi v
// from +z, so the top row is the zenith. `rotationDegrees` turns the map about +z (positive is
// counter-clockwise seen from above); `scale` multiplies its radiance.
#pragma once

#include <string>
#include <vector>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/sampling.h"

namespace nestlight::gi {

class EnvironmentMap {
 public:
  EnvironmentMap() = default;  // black, never sampled
  EnvironmentMap(HdrImage image, float rotationDegrees = 0, float scale = 1);
  static EnvironmentMap load(const std::string& path, float rotationDegrees = 0, float scale = 1);
  // A constant environment of radiance L everywhere (the furnace).
  static EnvironmentMap constant(const Rgb& L);

  Rgb eval(const glm::vec3& direction) const;  // radiance arriving from `direction` (unit, world)

  struct Sample {
    glm::vec3 direction{0.0f};  // towards the environment
    Rgb radiance{0.0f};
    float pdf = 0;  // per solid angle; 0 when the map is black
  };
  Sample sample(glm::vec2 u) const;
  float pdf(const glm::vec3& direction) const;

  bool black() const { return black_; }
  // Non-finite or negative texels replaced by 0 when the map was built.
  size_t invalidTexels() const { return invalidTexels_; }
  const HdrImage& image() const { return image_; }
  float rotationDegrees() const { return rotation_; }
  float scale() const { return scale_; }

 private:
  glm::vec2 uvFromDirection(const glm::vec3& d) const;
  glm::vec3 directionFromUv(glm::vec2 uv) const;
  // The texel a direction falls in; false for an empty map or a non-finite or zero direction.
  bool texelOf(const glm::vec3& direction, int* x, int* y) const;

  HdrImage image_;
  Distribution2D distribution_;
  float rotation_ = 0, scale_ = 1;
  bool black_ = true;
  size_t invalidTexels_ = 0;
  std::vector<double> rowCos_;  // cos theta at the height+1 row edges, top first
  double totalPower_ = 0;       // sum over texels of luminance * solid angle (unscaled)
};

}  // namespace nestlight::gi
