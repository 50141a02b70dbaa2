// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, step 2: the
// photograph's exposure from pairs of scan and photograph luminances (registered: the pixels the
// scan covers in the photograph's own view; unregistered: the matches under t_h, matching once
// more when the histogram's answer was far off), and the checks that refuse to write a layer
// resting on a wrong exposure. The paper has the histogram search alone (photo_exposure.cpp);
// the pairs and checks are ours (docs/HDR.md).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "expand/expansion.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr::expand {

void Expansion::recordPairs(const PairEstimate& pe) {
  checks.spreadStops = pe.spreadStops;
  checks.slope = pe.slope;
  checks.highlightSlope = pe.highlightSlope;
  checks.pairs = pe.pairs;
}

// Checks of the exposure's pairs (the matched share is checked after back-projection). A forced
// exposure is measured all the same, for the record, but the caller vouches for it.
std::vector<std::string> Expansion::exposureFailures() const {
  std::vector<std::string> f;
  char buf[400];
  if (checks.pairs < o.minPairs) {
    std::snprintf(
        buf, sizeof buf,
        "only %llu pixel pairs that the renderings explain and the scan recorded unclipped "
        "(at least %llu): the exposure rests on nothing",
        (unsigned long long)checks.pairs, (unsigned long long)o.minPairs);
    f.push_back(buf);
  } else if (checks.spreadStops > o.maxSpreadStops) {
    std::snprintf(
        buf, sizeof buf,
        "the log ratios between the scan's colour and the photograph spread over %.2f stops "
        "(at most %.2f; %llu pixel pairs, slope %.2f where a pure exposure change gives 1): "
        "the photograph's tone is not an exposure change of the scan's colour, or the pairs "
        "are of different things",
        checks.spreadStops, o.maxSpreadStops, (unsigned long long)checks.pairs, checks.slope);
    f.push_back(buf);
  }
  if (checks.pairs >= o.minPairs && checks.highlightSlope > o.maxHighlightSlope) {
    std::snprintf(
        buf, sizeof buf,
        "towards the clipping the photograph's tone grows %.2f times as fast as the scan's in "
        "log "
        "terms (at most %.2f; 1 is an exposure change): the values beyond the clipping would "
        "overshoot the truth",
        checks.highlightSlope, o.maxHighlightSlope);
    f.push_back(buf);
  }
  if (rep.log2Exposure < checks.rangeLo || rep.log2Exposure > checks.rangeHi) {
    std::snprintf(
        buf, sizeof buf,
        "the exposure 2^%.2f is outside the plausible range 2^%.2f to 2^%.2f (from where the "
        "photograph's brightest value reaches %.2f times the scan's clipping to where its "
        "darkest "
        "percentile clips)",
        rep.log2Exposure, checks.rangeLo, checks.rangeHi, o.minHeadroom);
    f.push_back(buf);
  }
  return f;
}

void Expansion::stopOnFailures(const std::vector<std::string>& failed) {
  if (failed.empty()) return;
  checks.failed.insert(checks.failed.end(), failed.begin(), failed.end());
  if (o.force) {
    for (const auto& f : failed) rep.warnings.push_back(f);
    return;
  }
  std::string msg = "the HDR layer would not be trusted, so none was written: ";
  for (size_t i = 0; i < failed.size(); ++i) msg += (i ? "; " : "") + failed[i];
  char buf[160];
  std::snprintf(buf, sizeof buf, " (exposure 2^%.2f, found from %s).", rep.log2Exposure,
                checks.method.c_str());
  msg += buf;
  msg += o.photoView ? ""
                     : " Pass the photograph's camera (--photo-view cams.json) so that only the "
                       "pixels the scan covers count.";
  msg += o.photoMask.empty()
             ? " Pass a mask (--photo-mask mask.png, white where the photograph shows the "
               "scanned scene) to leave out what the scan lacks."
             : "";
  msg +=
      " Pass the exposure if you know it (--exposure STOPS, log2 of the factor from the "
      "photograph's values to the "
      "scan's, 1 being the scan's clipping), or --force to write the layer anyway.";
  throw Error(msg);
}

// Registered: pairs where the scan renders in the photograph's own view (its coverage), never
// the background the scan lacks.
PairEstimate Expansion::photoViewPairs() const {
  const HdrImage ldr = renderings[0].image();
  std::vector<float> scanY, photoYs;
  for (size_t i = 0; i < ldr.pixels(); ++i) {
    if (!renderings[0].covered(i) || (!smallMask.empty() && !smallMask[i])) continue;
    scanY.push_back(
        linearLuminance(ldr.get(int(i % size_t(ldr.width)), int(i / size_t(ldr.width)))));
    photoYs.push_back(luminance(Rgb(small.rgb[3 * i], small.rgb[3 * i + 1], small.rgb[3 * i + 2])));
  }
  return estimateExposureFromPairs(scanY, photoYs, 0.02, o.overexposed, photoClip);
}

void Expansion::photoViewExposure() {
  photoClip = 0.99 * double(*std::max_element(positiveY.begin(), positiveY.end()));
  if (o.photoView && !o.log2Exposure) {
    const auto t = Clock::now();
    const PairEstimate pe = photoViewPairs();
    recordPairs(pe);
    if (pe.usable) rep.log2Exposure = pe.log2Exposure;
    stopOnFailures(exposureFailures());
    rep.seconds["exposure"] = rep.seconds["exposure"].get<double>() + seconds(t);
  }
}

void Expansion::settleExposure() {
  if (!o.photoView && !o.log2Exposure) {
    // Unregistered: the exposure from the matches that pass t_h. When it moves the histogram's
    // answer by more than half a stop, the matching is repeated once at the new exposure (the
    // matches were made against a photograph exposed wrongly, so they are fewer and poorer).
    PairEstimate pe =
        estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip);
    if (pe.usable && pe.pairs >= o.minPairs &&
        std::fabs(pe.log2Exposure - rep.log2Exposure) > 0.5) {
      rep.log2Exposure = pe.log2Exposure;
      checks.rematches++;
      match(float(std::exp2(rep.log2Exposure)));
      pe = estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip);
    }
    recordPairs(pe);
    if (pe.usable && pe.pairs >= o.minPairs) {
      // The values fetched at the matches scale with the exposure: rescale rather than match again.
      const float k = float(std::exp2(pe.log2Exposure - rep.log2Exposure));
      for (auto& e : expanded)
        for (float& v : e.hdr.rgb) v *= k;
      rep.log2Exposure = pe.log2Exposure;
    }
    stopOnFailures(exposureFailures());
  } else if (o.log2Exposure) {
    // Forced: measured for the record at the registered view's coverage or at the matches.
    if (o.photoView) {
      recordPairs(photoViewPairs());
    } else {
      recordPairs(
          estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip));
    }
  }
}

}  // namespace nestlight::gi::hdr::expand
