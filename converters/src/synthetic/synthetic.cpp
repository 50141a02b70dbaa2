// Seeded synthetic point source (openSynthetic).
//
// Sources:
//  - PDAL's readers.faux (https://pdal.io/en/latest/stages/readers.faux.html): a reader that
//    makes points instead of parsing them, for tests and benchmarks.
//  - SplitMix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators",
//    OOPSLA 2014; constants as in Vigna's splitmix64.c): a counter-based generator, so point i
//    is a pure function of (seed, i) and batches can be cut anywhere (and filled in parallel).
//  - Uniform area sampling of spheres (Archimedes: z uniform in [-1, 1]) and rectangles:
//    Pharr, Jakob, Humphreys, "Physically Based Rendering" 4th ed., section A.5.
//  - Gaussian noise: the Irwin-Hall sum of four uniforms, rescaled to unit variance. It is
//    bounded (|g| <= 2*sqrt(3) < 4), which gives the 4-sigma clamp for free, and needs no log
//    or trigonometry, which keeps generation above 20 M points/s per core.
#include "nestlight/converters/synthetic.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

constexpr uint64_t kGolden = 0x9E3779B97F4A7C15ull;

inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// The random stream of one point: draw k is mix64(base + k * golden) with base itself a
// splitmix64 output for (seed, i). Streams of different points start at unrelated places, so
// they do not overlap in practice, and seeds do not merely permute the points (as seed ^ i would).
struct PointRng {
  uint64_t s;
  PointRng(uint64_t seedKey, uint64_t i) : s(mix64(seedKey + i * kGolden)) {}
  uint64_t next() { return mix64(s += kGolden); }
  // Two uniforms in [0, 1) from one draw, 32 bits each: positions resolve size / 2^32 (25 nm at
  // 100 m), far finer than any precision grid, for half the hashing. Through int64 because
  // x86-64 converts signed integers to double in one instruction and unsigned ones not.
  static double hi(uint64_t r) { return double(int64_t(r >> 32)) * 0x1.0p-32; }
  static double lo(uint64_t r) { return double(int64_t(r & 0xffffffffu)) * 0x1.0p-32; }
};

// Unit-variance approximate Gaussian from the four 16-bit parts of one draw; |g| <= 2*sqrt(3).
inline double gauss(uint64_t r) {
  const double sum = double((r & 0xffff) + ((r >> 16) & 0xffff) + ((r >> 32) & 0xffff) + (r >> 48));
  return ((sum + 2.0) * (1.0 / 65536.0) - 2.0) * std::numbers::sqrt3;
}

// Round to nearest (ties to even) for |v| < 2^51, as exactly as nearbyint() but inline: adding
// and subtracting 1.5 * 2^52 leaves no fraction bits. Monotone in v, which the bounds rely on.
inline double roundNearest(double v) {
  constexpr double kMagic = 6755399441055744.0;  // 1.5 * 2^52
  double t = v + kMagic;
  asm("" : "+x"(t));  // keeps -ffast-math from folding (v + M) - M to v; costs nothing
  return t - kMagic;
}

// Triangle wave in 1/512ths, [0, 512], period 1, for t > -1024: a smooth-looking (piecewise
// linear) colour variation in integer arithmetic, without sin() or floor().
inline int tri512(double t) {
  const int frac = int(int64_t((t + 1024.0) * 512.0) & 511);
  return std::abs(2 * frac - 512);
}

inline uint16_t toU16(double v) {
  return static_cast<uint16_t>(std::clamp(v, 0.0, 65535.0) + 0.5);
}

// One primitive of the Surfaces scene, in unit coordinates (the scene fills [0,1]^2 x [0,0.3]).
struct Prim {
  enum Type { Rect, Sphere, Dome, Cylinder } type;
  std::array<double, 3> c;          // Rect: corner; Sphere/Dome: centre; Cylinder: base centre
  std::array<double, 3> e1, e2, n;  // Rect: edges and outward normal
  double radius = 0, height = 0;
  std::array<int, 3> albedo;  // 8-bit colour
  double reflectance;         // intensity scale in [0, 1]

  double area() const {
    constexpr double pi = std::numbers::pi;
    switch (type) {
      case Rect: {
        const auto& a = e1;
        const auto& b = e2;
        const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2],
                     cz = a[0] * b[1] - a[1] * b[0];
        return std::sqrt(cx * cx + cy * cy + cz * cz);
      }
      case Sphere:
        return 4 * pi * radius * radius;
      case Dome:
        return 2 * pi * radius * radius;
      case Cylinder:
        return 2 * pi * radius * height;
    }
    return 0;
  }
  void bounds(Box3d& b) const {
    switch (type) {
      case Rect:
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j)
            b.extend(c[0] + i * e1[0] + j * e2[0], c[1] + i * e1[1] + j * e2[1],
                     c[2] + i * e1[2] + j * e2[2]);
        return;
      case Sphere:
        b.extend(c[0] - radius, c[1] - radius, c[2] - radius);
        b.extend(c[0] + radius, c[1] + radius, c[2] + radius);
        return;
      case Dome:
        b.extend(c[0] - radius, c[1] - radius, c[2]);
        b.extend(c[0] + radius, c[1] + radius, c[2] + radius);
        return;
      case Cylinder:
        b.extend(c[0] - radius, c[1] - radius, c[2]);
        b.extend(c[0] + radius, c[1] + radius, c[2] + height);
        return;
    }
  }
};

// An axis-aligned box building: four walls (outward normals) and a flat roof.
void addBuilding(std::vector<Prim>& s, double x0, double y0, double x1, double y1, double h,
                 std::array<int, 3> wall, std::array<int, 3> roof) {
  const double dx = x1 - x0, dy = y1 - y0;
  s.push_back({Prim::Rect, {x0, y0, 0}, {dx, 0, 0}, {0, 0, h}, {0, -1, 0}, 0, 0, wall, 0.55});
  s.push_back({Prim::Rect, {x0, y1, 0}, {dx, 0, 0}, {0, 0, h}, {0, 1, 0}, 0, 0, wall, 0.55});
  s.push_back({Prim::Rect, {x0, y0, 0}, {0, dy, 0}, {0, 0, h}, {-1, 0, 0}, 0, 0, wall, 0.55});
  s.push_back({Prim::Rect, {x1, y0, 0}, {0, dy, 0}, {0, 0, h}, {1, 0, 0}, 0, 0, wall, 0.55});
  s.push_back({Prim::Rect, {x0, y0, h}, {dx, 0, 0}, {0, dy, 0}, {0, 0, 1}, 0, 0, roof, 0.35});
}

std::vector<Prim> buildingScene() {
  std::vector<Prim> s;
  // Ground: asphalt grey.
  s.push_back({Prim::Rect, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 0, 0, {96, 98, 92}, 0.25});
  addBuilding(s, 0.08, 0.08, 0.42, 0.36, 0.22, {178, 92, 68}, {70, 72, 80});    // brick
  addBuilding(s, 0.55, 0.10, 0.90, 0.30, 0.30, {205, 200, 188}, {60, 60, 64});  // render
  // A dome (a church's cupola, an observatory) and a ball (a statue base).
  s.push_back({Prim::Dome, {0.70, 0.68, 0}, {}, {}, {}, 0.17, 0, {225, 228, 235}, 0.8});
  s.push_back({Prim::Sphere, {0.25, 0.78, 0.06}, {}, {}, {}, 0.06, 0, {160, 150, 120}, 0.6});
  // A colonnade.
  Prim column{Prim::Cylinder, {0, 0.50, 0}, {}, {}, {}, 0.015, 0.20, {215, 205, 180}, 0.7};
  for (int k = 0; k < 6; ++k) {
    column.c[0] = 0.10 + 0.065 * k;
    s.push_back(column);
  }
  return s;
}

// Cornell-box-like room in [0,1]^3 (Goral et al. 1984's box, with a closed front wall so the
// scan is a closed room): walls face inwards.
std::vector<Prim> roomScene() {
  std::vector<Prim> s;
  const std::array<int, 3> white{200, 196, 188}, red{190, 40, 36}, green{44, 160, 60};
  s.push_back({Prim::Rect, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 0, 0, white, 0.7});  // floor
  s.push_back(
      {Prim::Rect, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}, 0, 0, white, 0.7});       // ceiling
  s.push_back({Prim::Rect, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}, 0, 0, red, 0.5});  // left
  s.push_back(
      {Prim::Rect, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, 0, 0, green, 0.5});  // right
  s.push_back({Prim::Rect, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}, 0, 0, white, 0.7});  // back
  s.push_back({Prim::Rect, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 0}, 0, 0, white, 0.7});  // front
  // The light: a patch just below the ceiling, facing down, saturated white in the scan.
  s.push_back({Prim::Rect,
               {0.38, 0.38, 0.995},
               {0.24, 0, 0},
               {0, 0.24, 0},
               {0, 0, -1},
               0,
               0,
               {255, 255, 255},
               1.0});
  addBuilding(s, 0.18, 0.55, 0.46, 0.83, 0.60, white, white);  // tall block
  addBuilding(s, 0.55, 0.18, 0.83, 0.46, 0.30, white, white);  // short block
  return s;
}

// A nave in [0,1] x [0,0.5] x [0,0.3]: hall walls facing inwards, two colonnades, an apse dome
// (a half dome on the east wall seen from inside is approximated by a full dome's inside).
std::vector<Prim> naveScene() {
  std::vector<Prim> s;
  const std::array<int, 3> stone{196, 186, 160}, floor{120, 104, 90}, plaster{226, 220, 206};
  const double W = 0.5, H = 0.3;
  s.push_back({Prim::Rect, {0, 0, 0}, {1, 0, 0}, {0, W, 0}, {0, 0, 1}, 0, 0, floor, 0.4});
  s.push_back({Prim::Rect, {0, 0, H}, {1, 0, 0}, {0, W, 0}, {0, 0, -1}, 0, 0, plaster, 0.6});
  s.push_back({Prim::Rect, {0, 0, 0}, {1, 0, 0}, {0, 0, H}, {0, 1, 0}, 0, 0, stone, 0.6});
  s.push_back({Prim::Rect, {0, W, 0}, {1, 0, 0}, {0, 0, H}, {0, -1, 0}, 0, 0, stone, 0.6});
  s.push_back({Prim::Rect, {0, 0, 0}, {0, W, 0}, {0, 0, H}, {1, 0, 0}, 0, 0, stone, 0.6});
  s.push_back({Prim::Rect,
               {1, 0, 0},
               {0, W, 0},
               {0, 0, H},
               {-1, 0, 0},
               0,
               0,
               {210, 170, 90},
               0.6});  // gilded east wall
  Prim column{Prim::Cylinder, {0, 0, 0}, {}, {}, {}, 0.018, H, stone, 0.7};
  for (int k = 0; k < 7; ++k) {
    column.c[0] = 0.12 + 0.12 * k;
    column.c[1] = 0.14;
    s.push_back(column);
    column.c[1] = W - 0.14;
    s.push_back(column);
  }
  return s;
}

class SyntheticReader final : public PointReader {
 public:
  explicit SyntheticReader(const SyntheticSpec& spec) : spec_(spec) {
    const std::string name = syntheticShapeName(spec.shape);
    if (!(spec.size > 0) || !std::isfinite(spec.size))
      throw Error("synthetic:" + name, "", "size must be positive");
    if (!(spec.noise >= 0)) throw Error("synthetic:" + name, "", "noise must be >= 0");
    for (size_t i = 0; i < kTrigSteps; ++i) {
      const double a = 2 * std::numbers::pi * double(i) / kTrigSteps;
      trig_[2 * i] = std::cos(a), trig_[2 * i + 1] = std::sin(a);
    }
    seedKey_ = mix64(spec.seed ^ 0x6E6573746C696768ull);  // "nestligh": seed 0 is no special case
    quantise_ = spec.precision > 0 && std::isfinite(spec.precision);
    if (quantise_ && (spec.size + 8 * spec.noise) / spec.precision > 0x1.0p50)
      throw Error("synthetic:" + name, "", "size / precision must stay below 2^50");
    invPrecision_ = quantise_ ? 1.0 / spec.precision : 0;

    PointLayout layout;
    if (spec.rgb) {
      rgbOff_ = layout.stride();
      layout.add({std::string(attr::kRgb), ScalarType::U16, 3, "synthetic, 8 bits * 257"});
    }
    if (spec.intensity) {
      intensityOff_ = layout.stride();
      layout.add({std::string(attr::kIntensity), ScalarType::U16, 1, "synthetic"});
    }
    if (spec.normals) {
      normalOff_ = layout.stride();
      layout.add({std::string(attr::kNormal), ScalarType::F32, 3, "synthetic, analytic"});
    }
    header_.path = "synthetic:" + name;
    header_.format = "synthetic";
    header_.declaredPoints = spec.points;
    header_.layout = std::move(layout);
    header_.rgbBits = spec.rgb ? 8 : 0;
    if (quantise_) {
      header_.scale = Vec3d{spec.precision, spec.precision, spec.precision};
      header_.offset = spec.origin;
    }
    header_.details = {{"shape", name},
                       {"seed", spec.seed},
                       {"points", spec.points},
                       {"size", spec.size},
                       {"noise", spec.noise},
                       {"precision", spec.precision},
                       {"origin", {spec.origin.x, spec.origin.y, spec.origin.z}}};

    // Shape bounds in metres relative to the origin, before quantisation.
    Box3d unit;
    if (primitiveScene()) {
      scene_ = spec.shape == SyntheticShape::Room   ? roomScene()
               : spec.shape == SyntheticShape::Nave ? naveScene()
                                                    : buildingScene();
      double total = 0;
      for (const Prim& p : scene_) total += p.area();
      double acc = 0;
      for (const Prim& p : scene_) {
        acc += p.area();
        cdf_.push_back(acc / total);
        p.bounds(unit);
      }
      cdf_.back() = 1.0;
      // start_[b]: the primitive at the start of bucket b; maxSteps_: the most primitive
      // boundaries inside one bucket. cdf_.back() == 1 > sel stops every step at the end.
      for (size_t b = 0, k = 0; b < kBuckets; ++b) {
        while (double(b) / kBuckets >= cdf_[k]) ++k;
        start_[b] = uint8_t(k);
        size_t e = k;
        while (double(b + 1) / kBuckets > cdf_[e]) ++e;
        maxSteps_ = std::max(maxSteps_, int(e - k));
      }
    } else if (spec.shape == SyntheticShape::Cube) {
      unit.extend(0, 0, 0), unit.extend(1, 1, 1);
    } else if (spec.shape == SyntheticShape::Plane) {
      unit.extend(0, 0, 0), unit.extend(1, 1, 0);
    } else {
      unit.extend(0.5, 0.5, 0.5);
    }
    // Noise along the normal is bounded by 2*sqrt(3) sigma; 4 sigma is the documented clamp.
    const double margin = primitiveScene() ? 4 * spec.noise : 0;
    Box3d b;
    for (int a = 0; a < 3; ++a) {
      // world() is monotone in its argument, so the images of the extremes bound every point.
      b.min[a] = world(a, unit.min[a] * spec.size - margin);
      b.max[a] = world(a, unit.max[a] * spec.size + margin);
    }
    header_.declaredBounds = b;
  }

  const SourceHeader& header() const override { return header_; }

  bool read(PointBatch& batch, size_t maxPoints) override {
    batch.clear();
    if (cursor_ >= spec_.points || maxPoints == 0) return false;
    const uint64_t n = std::min<uint64_t>(maxPoints, spec_.points - cursor_);
    const size_t stride = header_.layout.stride();
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * stride);
    const uint64_t first = cursor_;
    auto fill = [&](uint64_t lo, uint64_t hi) {
      for (uint64_t k = lo; k < hi; ++k)
        generate(first + k, &batch.xyz[k * 3], batch.attrs.data() + k * stride);
    };
    // Points are independent, so large batches are filled in parallel with identical results.
    constexpr uint64_t kGrain = 16384;
    if (n >= 4 * kGrain) {
      tbb::parallel_for(tbb::blocked_range<uint64_t>(0, n, kGrain),
                        [&](const tbb::blocked_range<uint64_t>& r) { fill(r.begin(), r.end()); });
    } else {
      fill(0, n);
    }
    cursor_ += n;
    return true;
  }

  void rewind() override { cursor_ = 0; }
  // "Bytes" are what the batches hold; only the ratio matters (progress).
  uint64_t bytesConsumed() const override { return cursor_ * bytesPerPoint(); }
  uint64_t bytesTotal() const override { return spec_.points * bytesPerPoint(); }

 private:
  uint64_t bytesPerPoint() const { return 24 + header_.layout.stride(); }
  bool primitiveScene() const {
    return spec_.shape == SyntheticShape::Surfaces || spec_.shape == SyntheticShape::Room ||
           spec_.shape == SyntheticShape::Nave;
  }

  // cos and sin of 2*pi*turns, turns in [0, 1): a table of 1024 angles and a rotation by the
  // remainder d < 2*pi/1024 with Taylor terms to d^5 (error < 1e-13). libm's sincos took an
  // eighth of the generation time.
  void cosSin(double turns, double& c, double& s) const {
    const double x = turns * kTrigSteps;
    const int i = std::min(int(x), int(kTrigSteps) - 1);
    const double d = (x - i) * (2 * std::numbers::pi / kTrigSteps), d2 = d * d;
    const double cd = 1 - d2 * (0.5 - d2 * (1.0 / 24)),
                 sd = d * (1 - d2 * (1.0 / 6 - d2 * (1.0 / 120)));
    c = trig_[2 * i] * cd - trig_[2 * i + 1] * sd;
    s = trig_[2 * i + 1] * cd + trig_[2 * i] * sd;
  }

  // Metres relative to the origin -> world coordinate on the precision grid.
  double world(int axis, double v) const {
    const double o = spec_.origin[axis];
    if (!quantise_) return o + v;
    return o + roundNearest(v * invPrecision_) * spec_.precision;
  }

  void generate(uint64_t i, double* xyz, uint8_t* attrs) const {
    PointRng rng(seedKey_, i);
    double p[3];                // unit coordinates
    double n[3] = {0, 0, 1};    // unit normal
    std::array<int, 3> albedo;  // 8-bit colour before shading
    double reflectance = 0.5;
    const double size = spec_.size;
    double m[3];       // metres relative to the origin
    uint32_t tex = 0;  // random bits for colour and intensity texture

    switch (spec_.shape) {
      case SyntheticShape::Surfaces:
      case SyntheticShape::Room:
      case SyntheticShape::Nave: {
        const uint64_t r1 = rng.next(), r2 = rng.next();
        tex = uint32_t(r2);
        const double sel = PointRng::hi(r1), u = PointRng::lo(r1), v = PointRng::hi(r2);
        // Branch-free steps: the primitive is random, so a data-dependent loop mispredicts.
        size_t k = start_[size_t(sel * kBuckets)];
        for (int step = 0; step < maxSteps_; ++step) k += sel >= cdf_[k];
        const Prim& pr = scene_[k];
        switch (pr.type) {
          case Prim::Rect:
            for (int a = 0; a < 3; ++a)
              p[a] = pr.c[a] + u * pr.e1[a] + v * pr.e2[a], n[a] = pr.n[a];
            break;
          case Prim::Sphere:
          case Prim::Dome: {
            const double z = pr.type == Prim::Sphere ? 2 * u - 1 : u;
            const double rho = std::sqrt(std::max(0.0, 1 - z * z));
            double c, sn;
            cosSin(v, c, sn);
            n[0] = rho * c, n[1] = rho * sn, n[2] = z;
            for (int a = 0; a < 3; ++a) p[a] = pr.c[a] + pr.radius * n[a];
            break;
          }
          case Prim::Cylinder: {
            cosSin(u, n[0], n[1]);
            n[2] = 0;
            for (int a = 0; a < 2; ++a) p[a] = pr.c[a] + pr.radius * n[a];
            p[2] = pr.c[2] + v * pr.height;
            break;
          }
        }
        const double g = spec_.noise * gauss(rng.next());
        for (int a = 0; a < 3; ++a) m[a] = p[a] * size + g * n[a];
        albedo = pr.albedo;
        reflectance = pr.reflectance;
        break;
      }
      case SyntheticShape::Cube: {
        const uint64_t r1 = rng.next(), r2 = rng.next();
        tex = uint32_t(r2);
        p[0] = PointRng::hi(r1), p[1] = PointRng::lo(r1), p[2] = PointRng::hi(r2);
        for (int a = 0; a < 3; ++a) m[a] = p[a] * size;
        // No surface here: the normal points away from the centre.
        const double d[3] = {p[0] - 0.5, p[1] - 0.5, p[2] - 0.5};
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len > 1e-12)
          for (int a = 0; a < 3; ++a) n[a] = d[a] / len;
        albedo = {40 + int(180 * p[0]), 40 + int(180 * p[1]), 40 + int(180 * p[2])};
        break;
      }
      case SyntheticShape::Plane: {
        const uint64_t r1 = rng.next();
        tex = uint32_t(rng.next());
        p[0] = PointRng::hi(r1), p[1] = PointRng::lo(r1), p[2] = 0;
        m[0] = p[0] * size, m[1] = p[1] * size, m[2] = 0;
        albedo = {150, 140, 120};
        break;
      }
      case SyntheticShape::Duplicates:
        p[0] = p[1] = p[2] = 0.5;
        m[0] = m[1] = m[2] = 0.5 * size;
        albedo = {200, 150, 100};
        break;
    }
    for (int a = 0; a < 3; ++a) xyz[a] = world(a, m[a]);

    if (spec_.shape == SyntheticShape::Duplicates) {
      // Exact duplicates: identical attributes too, no texture noise.
      if (rgbOff_ >= 0) {
        const uint16_t c[3] = {uint16_t(albedo[0] * 257), uint16_t(albedo[1] * 257),
                               uint16_t(albedo[2] * 257)};
        std::memcpy(attrs + rgbOff_, c, 6);
      }
      if (intensityOff_ >= 0) {
        const uint16_t it = 30000;
        std::memcpy(attrs + intensityOff_, &it, 2);
      }
      if (normalOff_ >= 0) {
        const float f[3] = {0, 0, 1};
        std::memcpy(attrs + normalOff_, f, 12);
      }
      return;
    }

    if (normalOff_ >= 0) {
      const float f[3] = {float(n[0]), float(n[1]), float(n[2])};
      std::memcpy(attrs + normalOff_, f, 12);
    }
    if (rgbOff_ < 0 && intensityOff_ < 0) return;
    // Shading that varies smoothly over metres-scale patterns (relative to the scene), plus a
    // little per-point texture noise, as a real scan's colour does; compression sees realistic
    // neighbour correlation.
    // Shade in 1/256ths: 0.72 + 0.18 * tri + 0.10 * tri.
    const int shade8 = 184 + ((46 * tri512(p[0] * 7 + p[1] * 3)) >> 9) +
                       ((26 * tri512(p[2] * 11 - p[1] * 5)) >> 9);
    if (rgbOff_ >= 0) {
      // Luminance noise -16..15 and per-channel noise -4..3 from the texture bits.
      const int lum = int(tex & 31) - 16;
      uint16_t c[3];
      for (int a = 0; a < 3; ++a) {
        const int v = ((albedo[a] * shade8) >> 8) + lum + int((tex >> (5 + 3 * a)) & 7) - 4;
        c[a] = uint16_t(std::clamp(v, 0, 255) * 257);
      }
      std::memcpy(attrs + rgbOff_, c, 6);
    }
    if (intensityOff_ >= 0) {
      const double noiseI = double((tex >> 14) & 2047) - 1023.5;
      const uint16_t it = toU16(65535.0 * reflectance * (0.55 + (0.45 / 256) * shade8) + noiseI);
      std::memcpy(attrs + intensityOff_, &it, 2);
    }
  }

  SyntheticSpec spec_;
  SourceHeader header_;
  std::vector<Prim> scene_;
  std::vector<double> cdf_;  // cumulative area fractions of scene_
  static constexpr size_t kTrigSteps = 1024;
  std::array<double, 2 * kTrigSteps> trig_;  // cos, sin of 2*pi*i/kTrigSteps (16 KB: L1)
  static constexpr size_t kBuckets = 256;
  std::array<uint8_t, kBuckets> start_{};
  int maxSteps_ = 0;
  uint64_t seedKey_ = 0;
  bool quantise_ = false;
  double invPrecision_ = 0;
  int rgbOff_ = -1, intensityOff_ = -1, normalOff_ = -1;
  uint64_t cursor_ = 0;
};

}  // namespace

std::unique_ptr<PointReader> openSynthetic(const SyntheticSpec& spec) {
  return std::make_unique<SyntheticReader>(spec);
}

std::optional<SyntheticShape> parseSyntheticShape(std::string_view name) {
  std::string s(name);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  if (s == "surfaces") return SyntheticShape::Surfaces;
  if (s == "cube") return SyntheticShape::Cube;
  if (s == "duplicates") return SyntheticShape::Duplicates;
  if (s == "plane") return SyntheticShape::Plane;
  if (s == "room") return SyntheticShape::Room;
  if (s == "nave") return SyntheticShape::Nave;
  return std::nullopt;
}

const char* syntheticShapeName(SyntheticShape shape) {
  switch (shape) {
    case SyntheticShape::Surfaces:
      return "surfaces";
    case SyntheticShape::Cube:
      return "cube";
    case SyntheticShape::Duplicates:
      return "duplicates";
    case SyntheticShape::Plane:
      return "plane";
    case SyntheticShape::Room:
      return "room";
    case SyntheticShape::Nave:
      return "nave";
  }
  return "?";
}

}  // namespace nestlight
