// Colour compensation between a photograph and a rendering of the scan (Rohmer, Jendersie and
// Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality for Mobile and
// non-Mobile Devices", IEEE TVCG 2017, section 4): pair selection (4.1), the per-channel scale A
// (4.2) and the regularised linear map C of eq. (2) (4.3).
#include "nestlight/gi/hdr/colour_compensation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr {

namespace {

// Signed, so that the round trip through a colour matrix that produces small negative values
// (cross-talk removal) is exact rather than clamped.
double signedPow(double v, double e) {
  return v < 0 ? -std::pow(-v, e) : std::pow(v, e);
}

bool finite3(const float* p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

Eigen::Vector3d load(const float* p) {
  return {double(p[0]), double(p[1]), double(p[2])};
}

// A colour's point in the HSV cylinder: (s cos 2 pi h, s sin 2 pi h, v).
//
// Why the disc and not (h, s) with a circular hue difference: hue is undefined for greys and
// numerically wild for nearly grey colours, which are the majority of pixels in real scenes. In
// (h, s) two near-greys of slightly different tint can be half the hue circle apart and would be
// rejected as if one were red and the other cyan; in the disc they are both close to the centre,
// so their distance is small, as their visible difference is. The disc also has no seam at h = 0.
// Its distances stay in [0, 2], so the paper's min(1, d) of eq. (1) still bounds the weights.
Eigen::Vector3d hsvPoint(const Eigen::Vector3d& display) {
  const double r = std::max(display.x(), 0.0), g = std::max(display.y(), 0.0),
               b = std::max(display.z(), 0.0);
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b});
  if (!(mx > 0)) return Eigen::Vector3d::Zero();
  const double chroma = mx - mn;
  if (!(chroma > 0)) return {0, 0, mx};
  double h;  // in sixths of the circle
  if (mx == r) {
    h = (g - b) / chroma;
  } else if (mx == g) {
    h = 2 + (b - r) / chroma;
  } else {
    h = 4 + (r - g) / chroma;
  }
  const double angle = h * (std::numbers::pi / 3);
  const double s = chroma / mx;
  return {s * std::cos(angle), s * std::sin(angle), mx};
}

// Display values of an image: a view of the pixels themselves when they are display-encoded, an
// encoded copy when they are linear.
class DisplayView {
 public:
  DisplayView(const HdrImage& image, const ColourCompensationOptions& options) {
    if (!options.inputsLinear) {
      data_ = image.rgb.data();
      return;
    }
    encoded_.resize(image.rgb.size());
    const double e = 1 / options.gamma;
    for (size_t i = 0; i < image.rgb.size(); i++) encoded_[i] = float(signedPow(image.rgb[i], e));
    data_ = encoded_.data();
  }
  const float* pixel(size_t i) const { return data_ + 3 * i; }

 private:
  std::vector<float> encoded_;
  const float* data_ = nullptr;
};

// The largest per-channel gradient magnitude, central differences on display values, borders
// replicated. With a coverage mask, neighbours without data count as the centre pixel: the edge of
// the scanned region is no edge of the scene, and its pixels are still good pairs.
double gradientAt(const DisplayView& image, int width, int height, int x, int y,
                  const std::vector<uint8_t>* coverage) {
  const size_t centre = size_t(y) * width + x;
  auto at = [&](int xx, int yy) {
    xx = std::clamp(xx, 0, width - 1);
    yy = std::clamp(yy, 0, height - 1);
    const size_t i = size_t(yy) * width + xx;
    return image.pixel(coverage && !(*coverage)[i] ? centre : i);
  };
  const float *left = at(x - 1, y), *right = at(x + 1, y), *up = at(x, y - 1), *down = at(x, y + 1);
  double largest = 0;
  for (int c = 0; c < 3; c++) {
    const double gx = 0.5 * (double(right[c]) - left[c]), gy = 0.5 * (double(down[c]) - up[c]);
    const double m = std::sqrt(gx * gx + gy * gy);
    // NaN neighbours make m NaN; they must not pass as a small gradient.
    if (!(m <= largest)) largest = std::isnan(m) ? INFINITY : m;
  }
  return largest;
}

double conditionNumber(const Eigen::Matrix3d& m) {
  if (!m.allFinite()) return INFINITY;
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::Matrix3d>(m).singularValues();
  return sv(2) > 0 ? sv(0) / sv(2) : INFINITY;
}

}  // namespace

double hsDistance(const Eigen::Vector3d& displayA, const Eigen::Vector3d& displayB) {
  return (hsvPoint(displayA).head<2>() - hsvPoint(displayB).head<2>()).norm();
}

double hsvDistance(const Eigen::Vector3d& displayA, const Eigen::Vector3d& displayB) {
  return (hsvPoint(displayA) - hsvPoint(displayB)).norm();
}

PairSelection selectColourPairs(const HdrImage& camera, const HdrImage& rendering,
                                const std::vector<uint8_t>& coverage,
                                const ColourCompensationOptions& options,
                                const std::optional<Eigen::Matrix3d>& previous) {
  if (camera.width != rendering.width || camera.height != rendering.height) {
    throw Error("colour compensation: the photograph is " + std::to_string(camera.width) + "x" +
                std::to_string(camera.height) + ", the rendering " +
                std::to_string(rendering.width) + "x" + std::to_string(rendering.height));
  }
  const size_t n = camera.pixels();
  if (camera.rgb.size() != 3 * n || rendering.rgb.size() != 3 * n) {
    throw Error("colour compensation: an image's pixel data does not match its size");
  }
  if (!coverage.empty() && coverage.size() != n) {
    throw Error("colour compensation: the coverage mask has " + std::to_string(coverage.size()) +
                " entries for " + std::to_string(n) + " pixels");
  }
  const std::vector<uint8_t>* mask = coverage.empty() ? nullptr : &coverage;
  const DisplayView cameraDisplay(camera, options), renderingDisplay(rendering, options);

  PairSelection selection;
  selection.classes.assign(n, PairClass::kAccepted);
  PairStatistics& stats = selection.statistics;
  stats.pixels = n;
  auto linear = [&](const float* raw) {
    const Eigen::Vector3d v = load(raw);
    return options.inputsLinear
               ? v
               : v.unaryExpr([&](double c) { return signedPow(c, options.gamma); }).eval();
  };

  for (int y = 0; y < camera.height; y++) {
    for (int x = 0; x < camera.width; x++) {
      const size_t i = size_t(y) * camera.width + x;
      const float* cameraRaw = &camera.rgb[3 * i];
      const float* renderingRaw = &rendering.rgb[3 * i];
      PairClass& cls = selection.classes[i];
      const Eigen::Vector3d u = load(cameraDisplay.pixel(i));
      if (!finite3(cameraRaw)) {
        cls = PairClass::kNonFinite;
        stats.nonFinite++;
        continue;
      }
      if (u.minCoeff() < options.minDisplay || u.maxCoeff() > options.maxDisplay) {
        cls = PairClass::kSaturated;
        stats.saturated++;
        continue;
      }
      if (mask && !(*mask)[i]) {
        cls = PairClass::kNoData;
        stats.noData++;
        continue;
      }
      if (!finite3(renderingRaw)) {
        cls = PairClass::kNonFinite;
        stats.nonFinite++;
        continue;
      }
      if (!(gradientAt(cameraDisplay, camera.width, camera.height, x, y, nullptr) <=
            options.maxGradient) ||
          !(gradientAt(renderingDisplay, camera.width, camera.height, x, y, mask) <=
            options.maxGradient)) {
        cls = PairClass::kGradient;
        stats.gradient++;
        continue;
      }
      const Eigen::Vector3d r = load(renderingDisplay.pixel(i));
      const double d = hsDistance(u, r);
      if (!(d <= options.maxHsDistance)) {
        cls = PairClass::kHsDistance;
        stats.hsDistance++;
        continue;
      }
      const Eigen::Vector3d uLinear = linear(cameraRaw);
      if (previous) {
        const Eigen::Vector3d predicted = ((*previous) * uLinear).unaryExpr([&](double c) {
          return signedPow(c, 1 / options.gamma);
        });
        if (!(hsvDistance(predicted, r) <= options.maxHsvDistance)) {
          cls = PairClass::kHsvDistance;
          stats.hsvDistance++;
          continue;
        }
      }
      selection.pairs.push_back({uLinear, linear(renderingRaw), d});
      stats.accepted++;
    }
  }
  return selection;
}

ColourCompensation fitColourCompensation(const std::vector<ColourPair>& pairs,
                                         const ColourCompensationOptions& options,
                                         const PairStatistics& statistics) {
  ColourCompensation result;
  result.statistics = statistics;

  // One pass: the sums of eq. (1)'s weighted colours for A, and U W^2 U^T, U W^2 R^T for C
  // (W_ii = sqrt(w_i), so W^2 holds the weights themselves).
  Eigen::Vector3d sumCamera = Eigen::Vector3d::Zero(), sumReference = Eigen::Vector3d::Zero();
  Eigen::Matrix3d uu = Eigen::Matrix3d::Zero(), ur = Eigen::Matrix3d::Zero();
  for (const ColourPair& p : pairs) {
    const double base = 1 - std::min(1.0, p.hsDistance);
    const double wA = std::pow(base, options.betaApproximation);
    const double wC = std::pow(base, options.betaLinear);
    sumCamera += wA * p.camera;
    sumReference += wA * p.reference;
    uu.noalias() += wC * p.camera * p.camera.transpose();
    ur.noalias() += wC * p.camera * p.reference.transpose();
  }

  // A channel with no weighted signal in either image cannot be scaled: no matrix from these pairs
  // could map it, and none would be invertible.
  const Eigen::Vector3d scale = sumReference.cwiseQuotient(sumCamera);
  if (pairs.empty() || !(sumCamera.minCoeff() > 0) || !(sumReference.minCoeff() > 0) ||
      !scale.allFinite()) {
    return result;  // identity, approximated, unusable
  }
  result.usable = true;
  result.approximation = scale.asDiagonal();
  result.matrix = result.approximation;
  result.approximated = true;

  if (pairs.size() >= size_t(std::max(options.minPairs, 0))) {
    const Eigen::Matrix3d lhs = uu + options.regularisation * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d rhs = ur + options.regularisation * result.approximation.transpose();
    // Without regularisation, colours that span less than three dimensions (all greys, one missing
    // channel) leave lhs singular; the solve would then return an arbitrary C.
    if (conditionNumber(lhs) < 1e12) {
      const Eigen::Matrix3d c = lhs.fullPivLu().solve(rhs).transpose();
      if (conditionNumber(c) <= options.maxConditionNumber) {
        result.matrix = c;
        result.approximated = false;
      }
    }
  }
  result.inverse = result.matrix.inverse();
  result.conditionNumber = conditionNumber(result.matrix);
  return result;
}

ColourCompensation estimateColourCompensation(const HdrImage& camera, const HdrImage& rendering,
                                              const std::vector<uint8_t>& coverage,
                                              const ColourCompensationOptions& options,
                                              const std::optional<Eigen::Matrix3d>& previous) {
  const PairSelection selection = selectColourPairs(camera, rendering, coverage, options, previous);
  return fitColourCompensation(selection.pairs, options, selection.statistics);
}

HdrImage linearFromDisplay(const HdrImage& display, double gamma) {
  HdrImage out = display;
  for (float& v : out.rgb) v = float(signedPow(v, gamma));
  return out;
}

HdrImage displayFromLinear(const HdrImage& linear, double gamma) {
  HdrImage out = linear;
  for (float& v : out.rgb) v = float(signedPow(v, 1 / gamma));
  return out;
}

HdrImage applyColourMatrix(const HdrImage& linear, const Eigen::Matrix3d& m) {
  HdrImage out = linear;
  for (size_t i = 0; i + 2 < out.rgb.size(); i += 3) {
    const Eigen::Vector3d c = m * load(&linear.rgb[i]);
    out.rgb[i] = float(c.x());
    out.rgb[i + 1] = float(c.y());
    out.rgb[i + 2] = float(c.z());
  }
  return out;
}

HdrImage toReferenceSpace(const HdrImage& cameraLinear, const ColourCompensation& compensation) {
  return applyColourMatrix(cameraLinear, compensation.matrix);
}

HdrImage toCameraSpace(const HdrImage& referenceLinear, const ColourCompensation& compensation) {
  return applyColourMatrix(referenceLinear, compensation.inverse);
}

}  // namespace nestlight::gi::hdr
