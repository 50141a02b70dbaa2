// Latitude-longitude environment maps and their importance sampling: Kronander et al., paper 001,
// section 7 ("tabulated row and column CDFs", after pbrt), and pbrt-v4 section 12.5.3 (image
// infinite lights: the sampling density is the texel's luminance weighted by sin theta).
//
// One refinement over pbrt's piecewise-constant-in-(u,v) table: a texel's weight is its luminance
// times its exact solid angle (the integral of sin theta over the row, not sin theta at the row's
// centre), and within a row cos theta is drawn uniformly. The density per solid angle is then
// exactly luminance / (sum of luminance * solid angle) inside every texel: constant over a
// texel as the radiance is, finite at the poles (no 1/sin theta), and uniform for a constant map
// of any resolution, 1x1 included. In pbrt's terms the (u,v) density is still
// pdf_uv = pdf_solid * 2 pi^2 sin theta, but it is continuous in v within a row.
#include "nestlight/gi/environment_map.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

constexpr double kPiD = 3.14159265358979323846;

bool validTexel(const float* p) {
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(p[c]) || p[c] < 0) return false;
  return true;
}

}  // namespace

EnvironmentMap::EnvironmentMap(HdrImage image, float rotationDegrees, float scale)
    : image_(std::move(image)), rotation_(rotationDegrees), scale_(scale) {
  NL_CHECK(image_.width >= 0 && image_.height >= 0 && image_.rgb.size() == image_.pixels() * 3);
  // A negative or NaN scale would give negative radiance that no pdf can importance-sample;
  // the scene reader rejects it with the file's name, so reaching here is a programming error.
  NL_CHECK_MSG(std::isfinite(scale_) && scale_ >= 0, "environment scale must be finite and >= 0");
  NL_CHECK_MSG(std::isfinite(rotation_), "environment rotation must be finite");
  const int w = image_.width, h = image_.height;
  if (image_.pixels() == 0) return;

  for (size_t i = 0; i < image_.pixels(); ++i) {
    float* p = &image_.rgb[3 * i];
    if (!validTexel(p)) {
      p[0] = p[1] = p[2] = 0;
      ++invalidTexels_;
    }
  }

  // Row edges in cos theta, in double: for thousands of rows 1 - cos(pi/h) is ~1e-7, below the
  // resolution of a float near 1.
  rowCos_.resize(size_t(h) + 1);
  for (int y = 0; y <= h; ++y) rowCos_[y] = std::cos(kPiD * y / h);
  rowCos_[0] = 1;
  rowCos_[h] = -1;

  std::vector<float> weight(image_.pixels());
  double total = 0;
  for (int y = 0; y < h; ++y) {
    const double rowSolidAngle = 2 * kPiD * (rowCos_[y] - rowCos_[y + 1]) / w;  // per texel
    for (int x = 0; x < w; ++x) {
      const double l = luminance(image_.get(x, y));
      // The table only needs relative weights; the normalisation is `totalPower_`, kept in
      // double so that a sun of 1e6 beside a sky of 1e-3 loses nothing.
      weight[size_t(y) * w + x] = float(l * (rowCos_[y] - rowCos_[y + 1]));
      total += l * rowSolidAngle;
    }
  }
  totalPower_ = total;
  black_ = !(total > 0 && std::isfinite(total)) || scale_ == 0;
  if (!black_) distribution_ = Distribution2D(weight, w, h);
}

EnvironmentMap EnvironmentMap::load(const std::string& path, float rotationDegrees, float scale) {
  return EnvironmentMap(readHdrImage(path), rotationDegrees, scale);
}

EnvironmentMap EnvironmentMap::constant(const Rgb& L) {
  HdrImage img(1, 1);
  img.set(0, 0, L);
  return EnvironmentMap(std::move(img));
}

glm::vec2 EnvironmentMap::uvFromDirection(const glm::vec3& d) const {
  // atan2 of (sin, cos) rather than acos(z): accurate near the poles and indifferent to |d|.
  const double theta = std::atan2(std::hypot(double(d.x), double(d.y)), double(d.z));
  double u = (std::atan2(double(d.y), double(d.x)) - double(rotation_) * (kPiD / 180)) / (2 * kPiD);
  u -= std::floor(u);
  const float uf = std::min(float(u), kOneMinusEpsilon);  // u just below 1 must not round to 1
  const float vf = std::clamp(float(theta / kPiD), 0.0f, 1.0f);
  return {uf, vf};
}

glm::vec3 EnvironmentMap::directionFromUv(glm::vec2 uv) const {
  const double phi = 2 * kPiD * uv.x + double(rotation_) * (kPiD / 180);
  const double theta = kPiD * uv.y;
  const double s = std::sin(theta);
  return {float(s * std::cos(phi)), float(s * std::sin(phi)), float(std::cos(theta))};
}

bool EnvironmentMap::texelOf(const glm::vec3& direction, int* x, int* y) const {
  if (image_.pixels() == 0) return false;
  if (!std::isfinite(direction.x) || !std::isfinite(direction.y) || !std::isfinite(direction.z))
    return false;
  if (direction.x == 0 && direction.y == 0 && direction.z == 0) return false;
  const glm::vec2 uv = uvFromDirection(direction);
  *x = std::min(int(uv.x * float(image_.width)), image_.width - 1);
  *y = std::min(int(uv.y * float(image_.height)), image_.height - 1);
  return true;
}

Rgb EnvironmentMap::eval(const glm::vec3& direction) const {
  int x, y;
  if (!texelOf(direction, &x, &y)) return Rgb(0.0f);
  return image_.get(x, y) * scale_;
}

float EnvironmentMap::pdf(const glm::vec3& direction) const {
  int x, y;
  if (black_ || !texelOf(direction, &x, &y)) return 0;
  return float(double(luminance(image_.get(x, y))) / totalPower_);
}

EnvironmentMap::Sample EnvironmentMap::sample(glm::vec2 u) const {
  Sample s;
  if (black_) return s;
  float pdfUv;
  const glm::vec2 uv = distribution_.sampleContinuous(u, &pdfUv);
  const int h = image_.height;
  const int row = std::min(int(uv.y * float(h)), h - 1);
  // The table is piecewise constant in v, so the position inside the row is uniform; mapping it
  // linearly to cos theta makes the texel's density per solid angle constant.
  const double t = std::clamp(double(uv.y) * h - row, 0.0, 1.0);
  const double c = rowCos_[row] + t * (rowCos_[row + 1] - rowCos_[row]);
  const float v = float(std::acos(std::clamp(c, -1.0, 1.0)) / kPiD);
  s.direction = directionFromUv({uv.x, v});
  // Radiance and pdf come from the direction, not the table entry, so that sample() and
  // pdf()/eval() agree exactly (MIS weights computed on either side match); a direction that
  // rounds across a texel edge lands on its neighbour's values, an error of measure ~1e-7.
  s.radiance = eval(s.direction);
  s.pdf = pdf(s.direction);
  return s;
}

}  // namespace nestlight::gi
