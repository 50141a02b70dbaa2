// Colour compensation between a photograph and a rendering of the scan from the same view (Rohmer,
// Jendersie and Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality
// for Mobile and non-Mobile Devices", IEEE TVCG 2017, section 4). The photograph is in an unknown
// colour space (exposure, white balance and contrast chosen by the camera); the rendering of the
// point cloud defines the reference colour space. Pixel pairs that probably show the same surface
// are selected (4.1), a per-channel scale A is fitted as a coarse backup (4.2), and a 3x3 linear
// map C from camera to reference linear RGB is fitted by weighted least squares regularised towards
// A (4.3, eq. 2). C^-1 brings composites rendered in the reference space back to the camera's.
//
// Both images are display-encoded by default and decoded with a plain 2.2 gamma curve before
// fitting: the camera's response curve is unknown, and the paper reports good results assuming
// 2.2. The fit always happens in linear RGB, because exposure and white balance are linear there.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "nestlight/gi/hdr_image.h"

namespace nestlight::gi::hdr {

struct ColourCompensationOptions {
  // The transfer curve of both inputs: linear = display^gamma. The saturation, gradient and HSV
  // tests always work on display values (linear inputs are encoded with this curve for them), so
  // the thresholds below mean the same whether or not the inputs are linear.
  double gamma = 2.2;
  bool inputsLinear = false;

  // A camera pixel with any channel outside [minDisplay, maxDisplay] (display values) is under- or
  // over-saturated: clipping destroyed its relation to the scene's radiance.
  double minDisplay = 0.02;
  double maxDisplay = 0.98;

  // Largest allowed gradient magnitude (display values per pixel, central differences, largest of
  // the three channels) in either image. Edges are where a small tracking error pairs a pixel with
  // the wrong surface.
  double maxGradient = 0.05;

  // Coarse filter: largest distance between the camera's and the rendering's colours in the
  // hue-saturation disc (see hsDistance). Generous, because the unknown white balance itself moves
  // colours in this plane.
  double maxHsDistance = 0.3;
  // Fine filter, only with a previous estimate c_{t-1}: largest distance in the HSV cylinder
  // between c_{t-1}(u) and r, brightness included (see hsvDistance). Tighter than the coarse one
  // because c_{t-1}(u) should already be close to r.
  double maxHsvDistance = 0.15;

  // Exponents of eq. (1): w = (1 - min(1, d_hs))^beta; the paper's values.
  double betaApproximation = 2;
  double betaLinear = 8;
  // The paper's gamma of eq. (2), the pull of C towards A; the paper's value. Not normalised by
  // the pairs' weights (as in the paper), so with many pairs the pull is tiny; it matters where the
  // pairs leave a direction of colour space unconstrained (e.g. all greys).
  double regularisation = 5e-2;

  // Below this many accepted pairs the linear map is not trusted and A is used (the paper's n).
  int minPairs = 2000;
  // C is rejected (and A used) when its 2-norm condition number exceeds this: an ill-conditioned
  // C has no useful inverse, and the inverse is needed to bring composites back.
  double maxConditionNumber = 1e4;
};

// Why a pixel was not used, the first reason that applies in this order.
enum class PairClass : uint8_t {
  kAccepted = 0,
  kNonFinite,    // the camera pixel, or a covered rendering pixel, is NaN or infinite
  kSaturated,    // the camera pixel is under- or over-saturated
  kNoData,       // the rendering has no point data there
  kGradient,     // a strong gradient in either image
  kHsDistance,   // the coarse hue-saturation filter
  kHsvDistance,  // the fine HSV filter against the previous estimate
};

struct PairStatistics {
  uint64_t pixels = 0;
  uint64_t accepted = 0;
  uint64_t nonFinite = 0;
  uint64_t saturated = 0;
  uint64_t noData = 0;
  uint64_t gradient = 0;
  uint64_t hsDistance = 0;
  uint64_t hsvDistance = 0;
};

// One accepted pair, linear RGB.
struct ColourPair {
  Eigen::Vector3d camera;
  Eigen::Vector3d reference;
  double hsDistance = 0;  // of the pair, what eq. (1) weighs by
};

struct PairSelection {
  std::vector<ColourPair> pairs;
  PairStatistics statistics;
  // Per pixel, top row first: the colour coding of the paper's figure 3.
  std::vector<PairClass> classes;
};

struct ColourCompensation {
  // Camera linear RGB -> reference linear RGB, and back.
  Eigen::Matrix3d matrix = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d inverse = Eigen::Matrix3d::Identity();
  // The per-channel scale A (identity when it could not be fitted).
  Eigen::Matrix3d approximation = Eigen::Matrix3d::Identity();
  // The matrix is A, not the linear fit: too few pairs or an ill-conditioned fit. The paper skips
  // capturing environment samples in such frames.
  bool approximated = true;
  // False when not even A could be fitted (no pairs, or a channel with no weighted signal): the
  // matrix is then the identity and the frame should not be used for colour.
  bool usable = false;
  double conditionNumber = 1;  // of matrix
  PairStatistics statistics;
};

// Section 4.1. camera and rendering must have the same size; coverage has one entry per pixel
// (non-zero: the rendering has point data there), or is empty when every pixel is covered. With
// previous, the fine HSV filter against c_{t-1} is applied too. Throws nestlight::Error on
// mismatched sizes.
PairSelection selectColourPairs(const HdrImage& camera, const HdrImage& rendering,
                                const std::vector<uint8_t>& coverage,
                                const ColourCompensationOptions& options = {},
                                const std::optional<Eigen::Matrix3d>& previous = std::nullopt);

// Sections 4.2 and 4.3 on selected pairs. statistics is copied into the result.
ColourCompensation fitColourCompensation(const std::vector<ColourPair>& pairs,
                                         const ColourCompensationOptions& options = {},
                                         const PairStatistics& statistics = {});

// Both steps.
ColourCompensation estimateColourCompensation(
    const HdrImage& camera, const HdrImage& rendering, const std::vector<uint8_t>& coverage,
    const ColourCompensationOptions& options = {},
    const std::optional<Eigen::Matrix3d>& previous = std::nullopt);

// The distance used by the coarse filter and eq. (1): between the points (s cos 2 pi h,
// s sin 2 pi h) of the two colours in the hue-saturation disc. Inputs are display-encoded RGB
// (negative channels count as 0). In [0, 2].
double hsDistance(const Eigen::Vector3d& displayA, const Eigen::Vector3d& displayB);
// The same in the HSV cylinder, with v = max(r, g, b) as the third coordinate.
double hsvDistance(const Eigen::Vector3d& displayA, const Eigen::Vector3d& displayB);

// linear = sign(v) |v|^gamma and its inverse, per channel (signed so that HDR and the negative
// values a colour matrix can produce survive a round trip).
HdrImage linearFromDisplay(const HdrImage& display, double gamma = 2.2);
HdrImage displayFromLinear(const HdrImage& linear, double gamma = 2.2);

// Every pixel p of a linear image replaced by m * p. No clamping: the result may be HDR.
HdrImage applyColourMatrix(const HdrImage& linear, const Eigen::Matrix3d& m);
// The photograph (linear) in the reference colour space, and a reference-space image (linear) in
// the photograph's.
HdrImage toReferenceSpace(const HdrImage& cameraLinear, const ColourCompensation& compensation);
HdrImage toCameraSpace(const HdrImage& referenceLinear, const ColourCompensation& compensation);

}  // namespace nestlight::gi::hdr
