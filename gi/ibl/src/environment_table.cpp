#include "nestlight/gi/ibl/environment_table.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>

namespace nestlight::gi::ibl {

namespace {

constexpr double kPiD = 3.14159265358979323846;

// A CDF over `f` (n values) into out[0..n]: 0 first, 1 last; an all-zero (or non-finite) row
// becomes uniform, as Distribution1D does, so the inversion never divides by zero.
double writeCdf(const double* f, size_t n, float* out) {
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += f[i];
  out[0] = 0;
  if (!(sum > 0) || !std::isfinite(sum)) {
    for (size_t i = 1; i <= n; ++i) out[i] = float(double(i) / double(n));
    return 0;
  }
  double run = 0;
  for (size_t i = 0; i < n; ++i) {
    run += f[i];
    out[i + 1] = float(run / sum);
  }
  out[n] = 1;
  return sum;
}

}  // namespace

EnvironmentTable buildEnvironmentTable(const EnvironmentMap& map) {
  const auto t0 = std::chrono::steady_clock::now();
  EnvironmentTable t;
  const HdrImage& img = map.image();
  const int w = std::max(img.width, 1), h = std::max(img.height, 1);
  const size_t rows = size_t(h), cols = size_t(w);
  t.data.assign(IBL_ENV_HEADER + 2 * (rows + 1) + rows * (cols + 1), 0.0f);
  float* rowCos = t.data.data() + IBL_ENV_HEADER;
  float* marginal = rowCos + rows + 1;
  float* conditional = marginal + rows + 1;
  std::vector<double> rowCosD(rows + 1);
  for (size_t y = 0; y <= rows; ++y) rowCosD[y] = std::cos(kPiD * double(y) / double(h));
  rowCosD[0] = 1, rowCosD[rows] = -1;
  for (size_t y = 0; y <= rows; ++y) rowCos[y] = float(rowCosD[y]);
  std::vector<double> rowWeight(rows, 0.0), f(cols);
  double power = 0;
  if (img.pixels() > 0) {
    for (size_t y = 0; y < rows; ++y) {
      const double band = rowCosD[y] - rowCosD[y + 1];
      for (size_t x = 0; x < cols; ++x) f[x] = double(luminance(img.get(int(x), int(y)))) * band;
      rowWeight[y] = writeCdf(f.data(), cols, conditional + y * (cols + 1));
      power += rowWeight[y] * 2 * kPiD / double(w);
    }
  }
  writeCdf(rowWeight.data(), rows, marginal);
  t.black = map.black();
  t.data[IBL_ENV_WIDTH] = std::bit_cast<float>(int32_t(img.pixels() ? img.width : 0));
  t.data[IBL_ENV_HEIGHT] = std::bit_cast<float>(int32_t(img.pixels() ? img.height : 0));
  t.data[IBL_ENV_POWER] = float(power);
  t.data[IBL_ENV_BLACK] = t.black ? 1.0f : 0.0f;
  t.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

}  // namespace nestlight::gi::ibl
