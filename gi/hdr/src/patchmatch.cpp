// Generalized PatchMatch (Barnes, Shechtman, Goldman and Finkelstein, "The Generalized PatchMatch
// Correspondence Algorithm", ECCV 2010) over similarity transforms, coarse to fine, as HDR
// expansion uses it (Sabbadin, Palma, Banterle, Boubekeur and Cignoni, "High Dynamic Range Point
// Clouds for Real-Time Relighting", 2019, section 4.1).
//
// Parallel and deterministic: each sweep runs over tiles as a wavefront (see sweep), and every
// pixel's random numbers come from a hash of (seed, level, sweep, pixel), so the result depends
// on neither the thread count nor the scheduling.
#include "nestlight/gi/hdr/patchmatch.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "nestlight/gi/sampling.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr {

namespace {

// Tile side of the wavefront sweep: 32 tiles per anti-diagonal at 512 pixels, enough for many
// cores, and a few hundred pixels per task so that scheduling costs little.
constexpr int kTile = 16;
constexpr int kCoarsestSide = 32;
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kTwoPi = 2.0f * kPi;
// Random search in angle and scale halves its window from the whole range this many times: the
// last window is pi/64 (under 3 degrees) and 1/64 of the log-scale range (about 2%); the finest
// sweeps' propagation and repeated search refine further.
constexpr int kAngleScaleSteps = 7;

// A candidate transform is skipped when no patch sample would move by this much (pixels) from
// the best one's: such twins (a converged neighbour's transform, propagated; overlapping coarse
// parents) cost a full patch comparison each and cannot change the match meaningfully.
constexpr float kSameTransform = 0.01f;

struct Match {
  glm::vec2 centre{0.0f};
  float angle = 0, scale = 1, ssd = kInf;
  // scale * (cos angle, sin angle), kept beside them: offsets map by complex product with it.
  glm::vec2 similarity{1.0f, 0.0f};
};

glm::vec2 apply(glm::vec2 similarity, glm::vec2 d) {
  return {similarity.x * d.x - similarity.y * d.y, similarity.y * d.x + similarity.x * d.y};
}

uint64_t splitmix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// PCG's streams with neighbouring increments are correlated, so pixels get well-mixed seeds on
// one stream instead of one stream each.
Rng pixelRng(uint64_t seed, int level, int sweep, size_t pixel) {
  uint64_t h = splitmix(seed);
  h = splitmix(h ^ (uint64_t(uint32_t(level)) << 32 | uint32_t(sweep)));
  return Rng(splitmix(h ^ uint64_t(pixel)));
}

HdrImage finite(const HdrImage& in) {
  HdrImage out = in;
  for (float& v : out.rgb)
    if (!std::isfinite(v)) v = 0;
  return out;
}

// A Gaussian pyramid step: [1 4 6 4 1]/16 both ways (edges clamped), keeping even pixels, so that
// coarse pixel q sits on fine pixel 2q and positions scale exactly by 2 between levels.
HdrImage downsample(const HdrImage& in) {
  static constexpr float kWeights[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
  const int w = in.width, h = in.height, cw = (w + 1) / 2, ch = (h + 1) / 2;
  HdrImage rows(cw, h), out(cw, ch);
  for (int y = 0; y < h; ++y)
    for (int i = 0; i < cw; ++i) {
      Rgb sum(0.0f);
      for (int k = -2; k <= 2; ++k)
        sum += kWeights[k + 2] * in.get(std::clamp(2 * i + k, 0, w - 1), y);
      rows.set(i, y, sum);
    }
  for (int j = 0; j < ch; ++j)
    for (int i = 0; i < cw; ++i) {
      Rgb sum(0.0f);
      for (int k = -2; k <= 2; ++k)
        sum += kWeights[k + 2] * rows.get(i, std::clamp(2 * j + k, 0, h - 1));
      out.set(i, j, sum);
    }
  return out;
}

// RGB padded to 4 floats (the fourth 0 on both sides of a difference): one aligned load per
// bilinear corner and one vector instruction per operation. GCC's and Clang's vector extension
// (SSE on x86-64, NEON on ARM), because neither compiler vectorises glm::vec4's arithmetic and
// this loop is most of the run time (a third faster so).
typedef float Float4 __attribute__((vector_size(16)));
struct Texel {
  Float4 v;
};

// A source patch: the part of the (2r+1)^2 window inside the source. Offsets outside are left out
// rather than clamped: the rendering's border is a crop of a view that the photograph may see
// beyond, and clamped streaks would match nothing there. The SSD of a cropped patch is scaled to
// the full patch's term count so that one threshold fits all pixels.
struct Patch {
  struct Sample {
    Texel colour;  // RGB, 0
    glm::vec2 offset;
  };
  std::vector<Sample> samples;         // outermost first (see LevelSolver's order_)
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // the offsets' bounding box, inclusive
  float normalisation = 1;             // full patch pixels / kept
};

class LevelSolver {
 public:
  LevelSolver(const HdrImage& source, const HdrImage& target, const std::vector<uint8_t>& mask,
              const PatchMatchOptions& options, int level)
      : s_(source), t_(target), mask_(mask), o_(options), level_(level), target_(t_.pixels()) {
    for (size_t i = 0; i < t_.pixels(); ++i)
      target_[i].v = Float4{t_.rgb[3 * i], t_.rgb[3 * i + 1], t_.rgb[3 * i + 2], 0.0f};
    // Patch offsets outermost first: a wrong angle or scale moves outer samples most, and a
    // wrong centre moves all alike, so early termination rejects bad candidates sooner.
    const int r = o_.patchRadius;
    reach_ = float(r) * std::sqrt(2.0f);
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) order_.emplace_back(dx, dy);
    std::stable_sort(order_.begin(), order_.end(), [](glm::ivec2 p, glm::ivec2 q) {
      return p.x * p.x + p.y * p.y > q.x * q.x + q.y * q.y;
    });
    logMin_ = std::log(o_.minScale);
    logRange_ = std::log(o_.maxScale) - logMin_;
  }

  // Calls f(x, y, i, patch) for every masked-in source pixel, rows in parallel.
  template <typename F>
  void forEachPixel(F f) const {
    tbb::parallel_for(0, s_.height, [&](int y) {
      Patch patch;
      for (int x = 0; x < s_.width; ++x) {
        const size_t i = index(x, y);
        if (!mask_[i]) continue;
        gather(x, y, patch);
        f(x, y, i, patch);
      }
    });
  }

  // The pixel's random transform of a level's start, kept when it is better than `best`.
  void considerRandom(Match& best, const Patch& patch, size_t i) const {
    Rng rng = pixelRng(o_.seed, level_, -1, i);
    const Match r = randomTransform(rng);
    consider(best, patch, r.centre, r.angle, r.scale, r.similarity);
  }

  // Random transforms everywhere (the coarsest level).
  void initRandom(std::vector<Match>& field) const {
    field.assign(s_.pixels(), Match{});
    forEachPixel([&](int x, int y, size_t i, const Patch& patch) {
      if (o_.identityStart) {
        // The same place in the target, scaled by the images' size ratio.
        const float ratio = float(t_.width) / float(s_.width);
        const float scale = std::clamp(ratio, o_.minScale, o_.maxScale);
        consider(field[i], patch, (glm::vec2(x, y) + 0.5f) * ratio - 0.5f, 0.0f, scale,
                 glm::vec2(scale, 0.0f));
      }
      considerRandom(field[i], patch, i);
    });
  }

  // Starts from the coarser level's field: the transforms of the 2x2 coarse pixels around each
  // pixel, carried over with their own rotation and scale (positions double), and one random
  // transform in case none of them fits.
  void initFromCoarse(std::vector<Match>& field, const std::vector<Match>& coarse, int cw,
                      int ch) const {
    field.assign(s_.pixels(), Match{});
    forEachPixel([&](int x, int y, size_t i, const Patch& patch) {
      Match best;
      for (int k = 0; k < 4; ++k) {
        const int qx = std::min(x / 2 + (k & 1), cw - 1), qy = std::min(y / 2 + (k >> 1), ch - 1);
        const Match& n = coarse[size_t(qy) * cw + qx];
        const glm::vec2 d = glm::vec2(x, y) - 2.0f * glm::vec2(qx, qy);
        consider(best, patch, 2.0f * n.centre + apply(n.similarity, d), n.angle, n.scale,
                 n.similarity);
      }
      considerRandom(best, patch, i);
      field[i] = best;
    });
  }

  // One sweep of propagation and random search, in scan order (reversed on odd sweeps). Tiles
  // run as a wavefront: those on one anti-diagonal in parallel, each scanned in order after the
  // tiles before it on both axes. Every pixel thus sees its two preceding neighbours already
  // updated, as a sequential scan would, so a good match can travel across the whole image in one
  // sweep; and what a pixel reads does not depend on the scheduling.
  void sweep(std::vector<Match>& field, int iteration) const {
    const bool reverse = iteration % 2 == 1;
    const int step = reverse ? -1 : 1;
    const int tilesX = (s_.width + kTile - 1) / kTile, tilesY = (s_.height + kTile - 1) / kTile;
    for (int diagonal = 0; diagonal < tilesX + tilesY - 1; ++diagonal) {
      const int first = std::max(0, diagonal - (tilesY - 1));
      const int last = std::min(tilesX - 1, diagonal);
      tbb::parallel_for(first, last + 1, [&](int tx) {
        const int ty = diagonal - tx;
        const int x0 = (reverse ? tilesX - 1 - tx : tx) * kTile;
        const int y0 = (reverse ? tilesY - 1 - ty : ty) * kTile;
        const int x1 = std::min(s_.width, x0 + kTile), y1 = std::min(s_.height, y0 + kTile);
        Patch patch;
        for (int row = 0; row < y1 - y0; ++row) {
          const int y = reverse ? y1 - 1 - row : y0 + row;
          for (int column = 0; column < x1 - x0; ++column) {
            const int x = reverse ? x1 - 1 - column : x0 + column;
            const size_t i = index(x, y);
            if (mask_[i]) update(field, patch, x, y, step, iteration);
          }
        }
      });
    }
  }

 private:
  size_t index(int x, int y) const { return size_t(y) * size_t(s_.width) + size_t(x); }

  void update(std::vector<Match>& field, Patch& patch, int x, int y, int step,
              int iteration) const {
    const size_t i = index(x, y);
    gather(x, y, patch);
    Match best = field[i];
    // Propagation: the neighbours already swept, their transform applied to the offset between
    // the two pixels (a rotated and scaled neighbour sits rotated and scaled).
    const int nx = x - step, ny = y - step;
    if (nx >= 0 && nx < s_.width && mask_[index(nx, y)]) {
      const Match& n = field[index(nx, y)];
      consider(best, patch, n.centre + apply(n.similarity, {float(step), 0.0f}), n.angle, n.scale,
               n.similarity);
    }
    if (ny >= 0 && ny < s_.height && mask_[index(x, ny)]) {
      const Match& n = field[index(x, ny)];
      consider(best, patch, n.centre + apply(n.similarity, {0.0f, float(step)}), n.angle, n.scale,
               n.similarity);
    }
    Rng rng = pixelRng(o_.seed, level_, iteration, i);
    randomSearch(best, rng, patch);
    field[i] = best;
  }

  void gather(int x, int y, Patch& patch) const {
    const int r = o_.patchRadius;
    patch.x0 = std::max(-r, -x), patch.x1 = std::min(r, s_.width - 1 - x);
    patch.y0 = std::max(-r, -y), patch.y1 = std::min(r, s_.height - 1 - y);
    patch.samples.clear();
    for (const glm::ivec2& d : order_) {
      if (d.x < patch.x0 || d.x > patch.x1 || d.y < patch.y0 || d.y > patch.y1) continue;
      const float* p = &s_.rgb[3 * index(x + d.x, y + d.y)];
      patch.samples.push_back({Texel{Float4{p[0], p[1], p[2], 0.0f}}, glm::vec2(d)});
    }
    patch.normalisation = float(order_.size()) / float(patch.samples.size());
  }

  // The SSD between the source patch and the target under (centre, angle, scale), or infinity as
  // soon as the partial sum reaches `bound` (the best so far): most candidates of random search
  // are far off and give up after a sample or two, which is where most of the time went.
  float distance(const Patch& patch, glm::vec2 centre, glm::vec2 similarity, float bound) const {
    const float a = similarity.x, b = similarity.y;
    // The patch's footprint is the parallelogram spanned by its corners: when it lies inside the
    // target (most candidates), samples need no clamping and always have a right and lower
    // neighbour. The margin covers rounding between the corners and the samples.
    const float xs[2] = {float(patch.x0), float(patch.x1)},
                ys[2] = {float(patch.y0), float(patch.y1)};
    float lo = kInf, hiX = -kInf, hiY = -kInf, loY = kInf;
    for (float dx : xs)
      for (float dy : ys) {
        const float x = centre.x + a * dx - b * dy, y = centre.y + b * dx + a * dy;
        lo = std::min(lo, x), hiX = std::max(hiX, x), loY = std::min(loY, y),
        hiY = std::max(hiY, y);
      }
    constexpr float kMargin = 1e-3f;
    const bool inside = lo >= 0 && loY >= 0 && hiX < float(t_.width - 1) - kMargin &&
                        hiY < float(t_.height - 1) - kMargin;
    return inside ? sum<false>(patch, centre, a, b, bound) : sum<true>(patch, centre, a, b, bound);
  }

  template <bool kClamp>
  float sum(const Patch& patch, glm::vec2 centre, float a, float b, float bound) const {
    const int w = t_.width, h = t_.height;
    const float maxX = float(w - 1), maxY = float(h - 1);
    const Texel* t = target_.data();
    const float rawBound = bound / patch.normalisation;
    float total = 0;
    for (const Patch::Sample& s : patch.samples) {
      float x = centre.x + a * s.offset.x - b * s.offset.y;
      float y = centre.y + b * s.offset.x + a * s.offset.y;
      int x0, y0, x1, y1;
      if constexpr (kClamp) {
        x = std::clamp(x, 0.0f, maxX), y = std::clamp(y, 0.0f, maxY);
        x0 = int(x), y0 = int(y);
        x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
      } else {
        x0 = int(x), y0 = int(y), x1 = x0 + 1, y1 = y0 + 1;
      }
      const float fx = x - float(x0), fy = y - float(y0);
      const Float4 p00 = t[size_t(y0) * w + x0].v;
      const Float4 p10 = t[size_t(y0) * w + x1].v;
      const Float4 p01 = t[size_t(y1) * w + x0].v;
      const Float4 p11 = t[size_t(y1) * w + x1].v;
      const Float4 top = p00 + fx * (p10 - p00), bottom = p01 + fx * (p11 - p01);
      const Float4 d = top + fy * (bottom - top) - s.colour.v;
      const Float4 dd = d * d;
      total += dd[0] + dd[1] + dd[2];
      if (total >= rawBound) return kInf;
    }
    return total * patch.normalisation;
  }

  // Keeps a candidate (its centre brought inside the target) when its patch is closer. The
  // angle, scale and similarity are taken as they are: a known match's, or reshaped's.
  void consider(Match& best, const Patch& patch, glm::vec2 centre, float angle, float scale,
                glm::vec2 similarity) const {
    centre = glm::clamp(centre, glm::vec2(0.0f), glm::vec2(t_.width - 1, t_.height - 1));
    if (best.ssd < kInf &&
        glm::length(centre - best.centre) + reach_ * glm::length(similarity - best.similarity) <
            kSameTransform)
      return;
    const float d = distance(patch, centre, similarity, best.ssd);
    if (d < best.ssd) best = {centre, angle, scale, d, similarity};
  }

  // The same for a new angle and scale: wrapped to [-pi, pi) (0 without rotation) and clamped
  // to the scale range.
  void considerReshaped(Match& best, const Patch& patch, glm::vec2 centre, float angle,
                        float scale) const {
    if (o_.rotation) {
      angle -= kTwoPi * std::floor((angle + kPi) / kTwoPi);
      if (!(angle >= -kPi && angle < kPi)) angle = -kPi;  // rounding at the wrap
    } else {
      angle = 0;
    }
    scale = std::clamp(scale, o_.minScale, o_.maxScale);
    consider(best, patch, centre, angle, scale,
             scale * glm::vec2(std::cos(angle), std::sin(angle)));
  }

  // Uniform in the target, in angle and in log scale; not evaluated (ssd infinite).
  Match randomTransform(Rng& rng) const {
    Match m;
    const glm::vec2 u = rng.uniform2();
    m.centre = u * glm::vec2(t_.width - 1, t_.height - 1);
    m.angle = o_.rotation ? kTwoPi * rng.uniform() - kPi : 0.0f;
    m.scale = std::exp(logMin_ + logRange_ * rng.uniform());
    m.similarity = m.scale * glm::vec2(std::cos(m.angle), std::sin(m.angle));
    return m;
  }

  // Random search around the best transform with exponentially shrinking windows: first in
  // position (from the whole target down to a pixel), then in angle and scale together. Searching
  // them apart matters: a position already right to a pixel would be lost by a joint candidate
  // whose position window is still wide, and a good angle by one whose angle window is.
  void randomSearch(Match& best, Rng& rng, const Patch& patch) const {
    float start = float(std::max(t_.width, t_.height));
    if (o_.searchRadius > 0)
      start = std::min(start, std::max(1.0f, o_.searchRadius / float(1 << level_)));
    for (float radius = start; radius >= 1.0f; radius *= 0.5f) {
      const glm::vec2 u = 2.0f * rng.uniform2() - 1.0f;
      consider(best, patch, best.centre + radius * u, best.angle, best.scale, best.similarity);
    }
    const bool searchAngle = o_.rotation, searchScale = logRange_ > 0;
    if (!searchAngle && !searchScale) return;
    float angleWindow = kPi, logWindow = logRange_;
    for (int k = 0; k < kAngleScaleSteps; ++k, angleWindow *= 0.5f, logWindow *= 0.5f) {
      const glm::vec2 u = 2.0f * rng.uniform2() - 1.0f;
      considerReshaped(best, patch, best.centre, best.angle + angleWindow * u.x,
                       best.scale * std::exp(logWindow * u.y));
    }
  }

  const HdrImage& s_;
  const HdrImage& t_;
  const std::vector<uint8_t>& mask_;
  const PatchMatchOptions& o_;
  int level_;
  std::vector<Texel> target_;
  std::vector<glm::ivec2> order_;
  float logMin_ = 0, logRange_ = 0;
  float reach_ = 0;  // the farthest patch offset's length
};

int automaticLevels(const HdrImage& source, const HdrImage& target) {
  int side = std::min({source.width, source.height, target.width, target.height}), levels = 1;
  while ((side + 1) / 2 >= kCoarsestSide) side = (side + 1) / 2, ++levels;
  return levels;
}

std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

}  // namespace

PatchMatchField generalizedPatchMatch(const HdrImage& source, const HdrImage& target,
                                      const PatchMatchOptions& options,
                                      const std::vector<uint8_t>* sourceMask) {
  if (source.pixels() == 0 || target.pixels() == 0)
    throw Error("", "patchmatch",
                "empty image (source " + std::to_string(source.width) + "x" +
                    std::to_string(source.height) + ", target " + std::to_string(target.width) +
                    "x" + std::to_string(target.height) + ")");
  if (source.rgb.size() != 3 * source.pixels() || target.rgb.size() != 3 * target.pixels())
    throw Error("", "patchmatch", "image pixel count does not match its size");
  if (sourceMask && sourceMask->size() != source.pixels())
    throw Error("", "patchmatch source mask",
                "has " + std::to_string(sourceMask->size()) + " entries for " +
                    std::to_string(source.pixels()) + " pixels");
  if (options.patchRadius < 0 || options.iterations < 0 || options.levels < 0)
    throw Error("", "patchmatch options", "patch radius, iterations and levels must be >= 0");
  if (!(options.minScale > 0 && options.minScale <= options.maxScale &&
        std::isfinite(options.maxScale)))
    throw Error("", "patchmatch options",
                "need 0 < minScale <= maxScale, got " + number(options.minScale) + " and " +
                    number(options.maxScale));

  const int levels = options.levels > 0 ? options.levels : automaticLevels(source, target);
  std::vector<HdrImage> sources{finite(source)}, targets{finite(target)};
  std::vector<std::vector<uint8_t>> masks{sourceMask ? *sourceMask
                                                     : std::vector<uint8_t>(source.pixels(), 1)};
  for (int l = 1; l < levels; ++l) {
    // Coarser levels match every pixel: they only seed the next level, and a mask's holes (gaps
    // between splats, a scan's scattered coverage) would cut propagation into islands.
    sources.push_back(downsample(sources.back()));
    masks.emplace_back(sources.back().pixels(), 1);
    targets.push_back(downsample(targets.back()));
  }

  std::vector<Match> field, coarse;
  for (int l = levels - 1; l >= 0; --l) {
    const LevelSolver solver(sources[l], targets[l], masks[l], options, l);
    if (l == levels - 1)
      solver.initRandom(field);
    else
      solver.initFromCoarse(field, coarse, sources[l + 1].width, sources[l + 1].height);
    for (int it = 0; it < options.iterations; ++it) solver.sweep(field, it);
    coarse.swap(field);
  }

  PatchMatchField out;
  out.width = source.width, out.height = source.height;
  out.targetWidth = target.width, out.targetHeight = target.height;
  out.position.assign(source.pixels(), glm::vec2(-1.0f));
  out.angle.assign(source.pixels(), 0.0f);
  out.scale.assign(source.pixels(), 1.0f);
  out.ssd.assign(source.pixels(), kInf);
  for (size_t i = 0; i < source.pixels(); ++i) {
    if (!masks[0][i]) continue;
    const Match& m = coarse[i];
    out.position[i] = m.centre, out.angle[i] = m.angle, out.scale[i] = m.scale, out.ssd[i] = m.ssd;
  }
  return out;
}

HdrImage fetch(const PatchMatchField& field, const HdrImage& image) {
  if (image.width != field.targetWidth || image.height != field.targetHeight)
    throw Error("", "patchmatch fetch",
                "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", the field points into " + std::to_string(field.targetWidth) + "x" +
                    std::to_string(field.targetHeight));
  HdrImage out(field.width, field.height);
  if (image.pixels() == 0) return out;
  const int w = image.width, h = image.height;
  for (int y = 0; y < field.height; ++y)
    for (int x = 0; x < field.width; ++x) {
      const size_t i = field.index(x, y);
      if (!std::isfinite(field.ssd[i])) continue;
      const glm::vec2 p = glm::clamp(field.position[i], glm::vec2(0.0f), glm::vec2(w - 1, h - 1));
      const int x0 = int(p.x), y0 = int(p.y);
      const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
      const float fx = p.x - float(x0), fy = p.y - float(y0);
      const Rgb top = glm::mix(image.get(x0, y0), image.get(x1, y0), fx);
      const Rgb bottom = glm::mix(image.get(x0, y1), image.get(x1, y1), fx);
      out.set(x, y, glm::mix(top, bottom, fy));
    }
  return out;
}

}  // namespace nestlight::gi::hdr
