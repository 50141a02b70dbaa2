// Pearson's chi-square goodness-of-fit test (Pearson 1900) for samplers of directions, in the
// manner of pbrt-v4's BSDF sampling tests and Mitsuba's ChiSquareTest: histogram many samples
// over theta x phi bins of the sphere, compare with the counts the sampler's claimed pdf
// predicts (the pdf integrated over each bin), pool sparse bins, and reject when the statistic
// is improbable under the chi-square distribution, at a significance Sidak-corrected for the
// number of tests. Header-only because tests/CMakeLists.txt globs only *_test.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/sampling.h"

namespace nestlight::gi::chi2 {

// Regularised upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a), a > 0, x >= 0.
// Implemented here because no dependency on DESIGN.md's list offers it (the standard library
// has only lgamma; Boost.Math is not among our packages). The lower series converges fast for
// x < a + 1, the continued fraction (modified Lentz) for x >= a + 1 (the usual split, e.g.
// Numerical Recipes 3rd ed., section 6.2); both to double precision.
inline double regularizedGammaQ(double a, double x) {
  if (!(a > 0) || !(x >= 0)) return std::nan("");
  if (x == 0) return 1;
  const double logPrefactor = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1) {
    // P(a, x) = x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a + 1) ... (a + n))
    double term = 1 / a, sum = term;
    for (int n = 1; n < 100000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * 1e-17) break;
    }
    return std::max(0.0, 1 - sum * std::exp(logPrefactor));
  }
  // Q(a, x) = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - 2 (2 - a) / ...))
  const double tiny = 1e-300;
  double b = x + 1 - a, c = 1 / tiny, d = 1 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < 1e-16) break;
  }
  return std::exp(logPrefactor) * h;
}

// P(X >= statistic) for X chi-square distributed with `dof` degrees of freedom.
inline double chi2Survival(double statistic, double dof) {
  return regularizedGammaQ(dof / 2, statistic / 2);
}

// Adaptive Simpson quadrature. At least `minDepth` bisections everywhere, so that a peak much
// narrower than [a, b] cannot hide between the first five samples; then bisection until the
// two halves agree with the whole to 15 tol (Richardson: Simpson's error is then ~tol), where
// tol is the larger of an absolute share (halved with each bisection, so the shares sum to
// absEps) and relEps of the piece's own integral (so a lobe of 1e5 is not chased to 1e-12).
template <class F>
double adaptiveSimpson(F& f, double a, double b, double absEps, double relEps, int minDepth,
                       int maxDepth) {
  struct Rec {
    F& f;
    double relEps;
    int minDepth, maxDepth;
    double run(double a, double b, double fa, double fm, double fb, double whole, double absEps,
               int depth) {
      double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
      double flm = f(lm), frm = f(rm);
      double left = (m - a) / 6 * (fa + 4 * flm + fm), right = (b - m) / 6 * (fm + 4 * frm + fb);
      double delta = left + right - whole;
      double tol = std::max(absEps, relEps * std::abs(left + right));
      if (depth >= maxDepth || (depth >= minDepth && std::abs(delta) <= 15 * tol))
        return left + right + delta / 15;
      return run(a, m, fa, flm, fm, left, absEps / 2, depth + 1) +
             run(m, b, fm, frm, fb, right, absEps / 2, depth + 1);
    }
  } rec{f, relEps, minDepth, maxDepth};
  double fa = f(a), fm = f(0.5 * (a + b)), fb = f(b);
  return rec.run(a, b, fa, fm, fb, (b - a) / 6 * (fa + 4 * fm + fb), absEps, 0);
}

struct QuadratureOptions {
  double absEps = 1e-10;  // per bin: 1e-4 of a count at 1e6 samples
  // Per piece, relative to its own integral. 1e-5 would be 10 counts in a bin of 1e6, harmless
  // in the statistic, but Simpson's error estimate is optimistic on a barely resolved peak and
  // the pieces' errors share a sign: at 1e-5, GGX at alpha 0.0025 around the pole lost 3e-5 of
  // its mass, enough to fail the pdf-integral check at 1e6 samples. 1e-6 gets it to 1e-8.
  double relEps = 1e-6;
  int minDepth = 3;  // 33 samples per bin side before the error estimate is trusted
  // 2^13 intervals per bin side (12 urad for 32 theta bins): bounds the work where the float
  // rounding of the directions (6e-8 rad, 1e-4 of a lobe 1e-3 rad wide) keeps a piece from
  // meeting relEps; still 100 samples across the narrowest lobe tested.
  int maxDepth = 12;
};

inline glm::dvec3 sphericalDirection(double theta, double phi) {
  double s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

// Integral of f(direction) over the patch [theta0, theta1] x [phi0, phi1] (solid angle measure).
// The integrand is sampled a hair (1e-5 of the patch) inside its edges: where f jumps at an edge
// (the horizon, a texel border) the value on the edge belongs to either side, and Simpson's end
// weights would otherwise chase that ambiguity to maxDepth for a wrong answer.
inline double integratePatch(const std::function<double(const glm::vec3&)>& f, double theta0,
                             double theta1, double phi0, double phi1,
                             const QuadratureOptions& q = {}) {
  const double dt = 1e-5 * (theta1 - theta0), dp = 1e-5 * (phi1 - phi0);
  auto outer = [&](double theta) {
    theta = std::clamp(theta, theta0 + dt, theta1 - dt);
    const double s = std::sin(theta);
    auto inner = [&](double phi) {
      phi = std::clamp(phi, phi0 + dp, phi1 - dp);
      return f(glm::vec3(sphericalDirection(theta, phi)));
    };
    return s * adaptiveSimpson(inner, phi0, phi1, q.absEps, q.relEps, q.minDepth, q.maxDepth);
  };
  return adaptiveSimpson(outer, theta0, theta1, q.absEps, q.relEps, q.minDepth, q.maxDepth);
}

// Integral over theta in [0, thetaMax], all phi, as a sum of thetaBins x phiBins patches.
inline double integrateSphere(const std::function<double(const glm::vec3&)>& f, double thetaMax,
                              int thetaBins, int phiBins, const QuadratureOptions& q = {}) {
  double sum = 0;
  for (int t = 0; t < thetaBins; ++t)
    for (int p = 0; p < phiBins; ++p)
      sum += integratePatch(f, thetaMax * t / thetaBins, thetaMax * (t + 1) / thetaBins,
                            2 * M_PI * p / phiBins, 2 * M_PI * (p + 1) / phiBins, q);
  return sum;
}

struct Chi2Options {
  int thetaBins = 32;  // even: the horizon is a bin edge, so a BSDF's jump there is on an edge
  int phiBins = 64;
  size_t samples = 1000000;
  double significance = 0.01;
  int tests = 1;           // chi-square tests in the family, for the Sidak correction
  double minExpected = 5;  // Pearson's statistic is chi-square distributed only for cells this full
  uint64_t seed = 1;
  QuadratureOptions quadrature;
};

struct Chi2Result {
  bool passed = false;
  double statistic = 0, pValue = 0, threshold = 0;
  int dof = 0;
  double pdfIntegral = 0;    // over the sphere, by quadrature
  size_t failedSamples = 0;  // the sampler returned nothing
  std::string message;       // why it failed, and the worst bins
};

// `sample` draws one direction (unit) or nothing (a rejected sample); `pdf` is its claimed density
// per solid angle. Rejections form one more cell, expected N (1 - integral of pdf).
inline Chi2Result chi2Test(const std::function<std::optional<glm::vec3>(Rng&)>& sample,
                           const std::function<double(const glm::vec3&)>& pdf,
                           const Chi2Options& o) {
  Chi2Result r;
  const int nt = o.thetaBins, np = o.phiBins;
  const size_t bins = size_t(nt) * np;
  std::vector<double> observed(bins + 1, 0.0), expected(bins + 1, 0.0);
  Rng rng(o.seed);
  for (size_t i = 0; i < o.samples; ++i) {
    std::optional<glm::vec3> d = sample(rng);
    if (!d) {
      observed[bins] += 1;
      continue;
    }
    double theta = std::atan2(std::hypot(double(d->x), double(d->y)), double(d->z));
    double phi = std::atan2(double(d->y), double(d->x));
    if (phi < 0) phi += 2 * M_PI;
    if (!std::isfinite(theta) || !std::isfinite(phi)) {
      r.message = "the sampler returned a non-finite direction";
      return r;
    }
    int t = std::clamp(int(theta / M_PI * nt), 0, nt - 1),
        p = std::clamp(int(phi / (2 * M_PI) * np), 0, np - 1);
    observed[size_t(t) * np + p] += 1;
  }
  r.failedSamples = size_t(observed[bins]);
  double integral = 0;
  for (int t = 0; t < nt; ++t)
    for (int p = 0; p < np; ++p) {
      double v = integratePatch(pdf, M_PI * t / nt, M_PI * (t + 1) / nt, 2 * M_PI * p / np,
                                2 * M_PI * (p + 1) / np, o.quadrature);
      expected[size_t(t) * np + p] = v * double(o.samples);
      integral += v;
    }
  r.pdfIntegral = integral;
  expected[bins] = std::max(0.0, 1 - integral) * double(o.samples);

  // A sample where the pdf integrates to nothing at all is a plain error, whatever the statistic.
  for (size_t i = 0; i < bins; ++i)
    if (observed[i] > 0 && expected[i] == 0) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "%g samples in bin theta %zu phi %zu where the pdf is zero",
                    observed[i], i / np, i % np);
      r.message = buf;
      return r;
    }

  // Pool the cells expected to hold fewer than minExpected samples, smallest first.
  std::vector<size_t> order(bins + 1);
  for (size_t i = 0; i <= bins; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return expected[a] < expected[b]; });
  std::vector<std::pair<double, double>> cells;  // (observed, expected)
  double poolObs = 0, poolExp = 0;
  size_t k = 0;
  for (; k < order.size() && expected[order[k]] < o.minExpected; ++k) {
    poolObs += observed[order[k]];
    poolExp += expected[order[k]];
  }
  for (; k < order.size(); ++k) cells.push_back({observed[order[k]], expected[order[k]]});
  if (poolExp > 0 || poolObs > 0) {
    if (poolExp >= o.minExpected || cells.empty()) {
      cells.push_back({poolObs, poolExp});
    } else {  // still too sparse: fold into the smallest full cell
      cells.front().first += poolObs;
      cells.front().second += poolExp;
    }
  }
  double stat = 0;
  std::vector<std::pair<double, size_t>> worst;
  for (size_t i = 0; i < cells.size(); ++i) {
    double diff = cells[i].first - cells[i].second;
    stat +=
        cells[i].second > 0 ? diff * diff / cells[i].second : (cells[i].first > 0 ? INFINITY : 0);
  }
  for (size_t i = 0; i <= bins; ++i)
    if (expected[i] >= o.minExpected) {
      double diff = observed[i] - expected[i];
      worst.push_back({diff * diff / expected[i], i});
    }
  std::sort(worst.begin(), worst.end(), std::greater<>());
  r.statistic = stat;
  r.dof = int(cells.size()) - 1;
  r.threshold = 1 - std::pow(1 - o.significance, 1.0 / std::max(1, o.tests));  // Sidak
  if (r.dof < 1) {
    r.message = "fewer than two cells after pooling: the test says nothing";
    return r;
  }
  r.pValue = chi2Survival(stat, r.dof);
  r.passed = r.pValue >= r.threshold;
  char buf[256];
  std::snprintf(
      buf, sizeof buf,
      "chi2 = %.1f, dof = %d, p = %.3g (threshold %.3g), pdf integral %.6f, %zu rejected;", stat,
      r.dof, r.pValue, r.threshold, integral, r.failedSamples);
  r.message = buf;
  for (size_t i = 0; i < std::min<size_t>(5, worst.size()); ++i) {
    size_t b = worst[i].second;
    if (b == bins)
      std::snprintf(buf, sizeof buf, " [rejected: obs %.0f exp %.1f]", observed[b], expected[b]);
    else
      std::snprintf(buf, sizeof buf, " [theta %zu phi %zu: obs %.0f exp %.1f]", b / np, b % np,
                    observed[b], expected[b]);
    r.message += buf;
  }
  return r;
}

}  // namespace nestlight::gi::chi2
