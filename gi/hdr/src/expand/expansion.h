// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4: the state one
// expansion's stages share, and the stages themselves, one file each in this folder (expand.h
// lists the stages and the colour conventions). Private to gi/hdr.
//
// The stages ran as one function whose lambdas shared its locals; the members keep those locals'
// names so that each stage reads as it did there. Nodes stream through every pass and per-point
// results live in a scratch file, so no member grows with the scan beyond its node table.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/exposure.h"
#include "nestlight/gi/hdr/patchmatch.h"
#include "nestlight/gi/hdr/poisson_infill.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi::hdr::expand {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

// The exposed photograph's value at masked-out pixels (display values are in [0, 1]): one such
// sample in a patch costs 99^2, far beyond any t_h.
constexpr float kMaskedOut = 100.0f;

double seconds(Clock::time_point since);

// The luminance of a rendering's display value, in the scan's linear units.
inline float linearLuminance(const Rgb& display) {
  return luminance(Rgb(linearFromDisplay(display.r), linearFromDisplay(display.g),
                       linearFromDisplay(display.b)));
}

// Per-point scratch record: the HDR colour so far and what happened to the point.
enum PointState : uint32_t {
  kKept = 0,       // not over-exposed: its LDR colour is its HDR colour
  kProjected = 1,  // over-exposed, given a matched HDR value
  kTarget = 2,     // over-exposed, no valid value: to in-fill
  kInfilled = 3,
  kIsland = 4,  // to in-fill, but no valid neighbour in reach: LDR kept
};
struct ScratchRecord {
  float rgb[3];
  uint32_t state;
};
static_assert(sizeof(ScratchRecord) == 16);

// The scratch file (scratch.cpp): one record per point of the scan, in node order.
class Scratch {
 public:
  Scratch(const fs::path& path, uint64_t points);
  ~Scratch();
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  void read(uint64_t first, size_t count, std::vector<ScratchRecord>& out) const;
  void write(uint64_t first, const std::vector<ScratchRecord>& in);

 private:
  void io(bool write, uint64_t first, size_t count, ScratchRecord* data) const;
  fs::path path_;
  int fd_ = -1;
};

// A uniform sample of the over-exposed points that does not depend on the order threads visit
// nodes in (reservoir sampling did, and so did the automatic views): every point gets a hash of
// its index in the scan, and the sample keeps the smallest hashes (bottom-k sampling).
struct Sample {
  struct Entry {
    uint64_t hash;
    glm::dvec3 position;
    glm::vec3 normal;
    bool operator<(const Entry& o) const { return hash < o.hash; }
  };
  std::vector<Entry> heap;  // a max-heap on hash, at most the sample's size
  std::vector<glm::dvec3> positions;
  std::vector<glm::vec3> normals;

  static uint64_t hashOf(uint64_t index);
  void offer(const Entry& e, size_t capacity);
  void finish();  // the sample in hash order
};

// One rendering's HDR mapping: the photograph's values at its matches.
struct Expanded {
  HdrImage hdr;            // exposure * photo at the match (linear, LDR units)
  std::vector<float> ssd;  // +inf: no point, or match rejected
};

class Expansion {
 public:
  // Opens the scan and checks the inputs; the layer's name is checked by the caller, before.
  Expansion(const fs::path& dir, const HdrImage& photo, const ExpandOptions& o,
            Clock::time_point t0);
  ExpandReport run();

  // Stages, in the order run() calls them.
  void statistics();            // statistics.cpp: pass A
  void photographExposure();    // photo_exposure.cpp: range and histogram search
  void chooseViews();           // views.cpp
  void render();                // views.cpp: pass B
  void photoViewExposure();     // exposure_checks.cpp: registered
  void preparePhotoCoverage();  // matching.cpp
  void match(float exposure);   // matching.cpp
  void settleExposure();        // exposure_checks.cpp: unregistered or forced
  void rejectStrays();          // strays.cpp
  void bound();                 // bound.cpp
  void backProject();           // back_projection.cpp: pass C
  void infill();                // infill.cpp: pass D
  void writeLayer();            // layer.cpp: pass E

  // Helpers the stages share.
  void progress(const std::string& stage, double f) const {
    if (o.progress) o.progress(stage, f);
  }
  bool maskedIn(size_t i) const { return o.photoMask.empty() || o.photoMask[i] != 0; }
  void matchView(size_t vi, float exposure);
  bool explainedTarget(glm::vec2 p) const;
  // Point i of n's HDR colour from the views' matches (c): false when none gave one; seen says
  // whether a view saw it at all. candidates is scratch space, kept between calls.
  bool projectPoint(const ScanNode& n, size_t i, double y,
                    std::vector<std::pair<glm::dvec3, double>>& candidates, glm::dvec3& c,
                    bool& seen) const;
  void recordPairs(const PairEstimate& pe);
  PairEstimate photoViewPairs() const;
  std::vector<std::string> exposureFailures() const;
  void stopOnFailures(const std::vector<std::string>& failed);
  void checkMatchedShare();
  std::vector<NodeKey> infillChunks();
  void infillChunk(const NodeKey& cell, const InfillOptions& io);

  const Clock::time_point t0;
  const fs::path& dir;
  const HdrImage& photo;
  const ExpandOptions& o;
  ExpandReport rep;
  ExposureChecks& checks = rep.checks;

  // The scan, its nodes in key order, and each node's first point in the scan's numbering.
  OctreeReader reader;
  const Metadata& meta;
  ScanAccess scan;
  std::vector<std::pair<NodeKey, HierarchyEntry>> nodes;
  std::vector<uint64_t> base;
  std::unordered_map<NodeKey, size_t, NodeKeyHash> nodeIndex;

  // Statistics and the photograph.
  Sample sample;
  Histogram scanHistogram;
  std::vector<float> photoY;     // the photograph's non-zero luminances, where masked in
  std::vector<float> positiveY;  // those positive and finite
  double photoMax = 0;
  HdrImage small;                  // the photograph as PatchMatch sees it
  std::vector<uint8_t> smallMask;  // the mask at that size; empty: none

  // Renderings and their matches.
  std::vector<Rendering> renderings;
  double photoClip = 0;
  std::vector<Expanded> expanded;
  HdrImage exposedDisplay;
  // Pairs at the matches that pass t_h (and are not blind): the unregistered exposure's evidence.
  std::vector<float> matchScanY, matchPhotoY;
  // The photograph's pixels a point may take its value from: registered, where the scan renders
  // in the photograph's own view; with a mask, where the mask lets it count; both, both.
  // Elsewhere the photograph shows what the scan lacks (sky, a lamp beyond it). Empty: every
  // pixel.
  std::vector<uint8_t> photoCoverage;
  float exposure = 0;  // the final exposure's factor, once settled

  // Back-projection's results.
  std::unique_ptr<Scratch> scratch;
  uint64_t targets = 0;  // points left to in-fill
};

}  // namespace nestlight::gi::hdr::expand
