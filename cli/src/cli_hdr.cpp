// `nestlight expand-hdr`: HDR expansion of a scan's colour from one HDR photograph.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>

#include "cli.h"
#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/views.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

namespace {

constexpr const char* kExpandHdrHelp =
    "Expand a scan's clipped LDR colour to HDR from one HDR photograph of part of the scene\n"
    "(Sabbadin et al. 2019): renders the scan from views that see its over-exposed points, "
    "finds\n"
    "the photograph's exposure, matches each rendering to the photograph with generalised\n"
    "PatchMatch (rotation and scale), back-projects the photograph's HDR values onto the points\n"
    "whose LDR luminance exceeds 0.9, and in-fills the rest in the gradient domain. The result "
    "is\n"
    "the octree's 'hdr' colour layer, written atomically beside the scan's colour (which is "
    "never\n"
    "changed); `verify` checks it, `info` shows it, `render --colour hdr` and scene files use "
    "it.\n"
    "The photograph needs no registration, but registered (--photo-view) its exposure comes "
    "from\n"
    "the pixels the scan covers, unregistered from the matches under t_h. The exposure is "
    "checked\n"
    "(spread and highlight slope of the log ratios between scan and photograph, a plausible\n"
    "range, the share of over-exposed points matched); when a check fails no layer is written\n"
    "and the error says what to pass (--photo-view, --photo-mask, --exposure, --force).\n"
    "Values are bounded by the photograph's largest times the exposure; registered, matches\n"
    "that land on background the scan lacks are rejected; a mask (--photo-mask) leaves out\n"
    "what it covers. `info` shows the exposure and the checks. Memory is bounded\n"
    "whatever the scan's size.\n"
    "Example: nestlight expand-hdr scan.octree --photo window.exr --auto-views 2";

// A pixel counts where the mask's largest channel is above half: a black-and-white mask from any
// paint program, 8 or 16 bits, or a float EXR.
std::vector<uint8_t> readPhotoMask(const std::string& path, const gi::HdrImage& photo) {
  const std::string ext = fs::path(path).extension().string();
  const gi::HdrImage m =
      (ext == ".png" || ext == ".PNG") ? gi::readPng(path) : gi::readHdrImage(path);
  if (m.width != photo.width || m.height != photo.height)
    throw Error(path, "",
                "the mask is " + std::to_string(m.width) + " x " + std::to_string(m.height) +
                    " pixels, the photograph " + std::to_string(photo.width) + " x " +
                    std::to_string(photo.height) + ": draw the mask at the photograph's size");
  std::vector<uint8_t> mask(m.pixels());
  size_t in = 0;
  for (size_t i = 0; i < m.pixels(); ++i) {
    const float v = std::max({m.rgb[3 * i], m.rgb[3 * i + 1], m.rgb[3 * i + 2]});
    mask[i] = v > 0.5f;  // NaN: out
    in += mask[i];
  }
  if (in == 0)
    throw Error(path, "", "the mask is black everywhere: no pixel of the photograph would count");
  return mask;
}

// The report as a user reads it: the exposure and its checks first, then where the points went.
void printReport(const gi::hdr::ExpandReport& r, const std::string& dir, const std::string& mode,
                 const gi::hdr::ExpandOptions& o) {
  std::printf("expand-hdr: %s, mode %s\n", dir.c_str(), mode == "rgb" ? "rgb" : "luminance");
  const auto& c = r.checks;
  std::printf("  exposure      2^%.3f from %s", r.log2Exposure, c.method.c_str());
  if (c.method == "matches") std::printf(" (histogram search 2^%.3f)", c.histogramLog2);
  std::printf(
      "\n  checks        %llu pixel pairs, log-ratio spread %.3f stops (at most %.2f), slope "
      "%.2f,\n"
      "                plausible 2^%.2f to 2^%.2f, %.1f%% of over-exposed points matched%s\n",
      (unsigned long long)c.pairs, c.spreadStops, o.maxSpreadStops, c.slope, c.rangeLo, c.rangeHi,
      100 * std::max(0.0, c.matchedShare),
      c.failed.empty() ? "" : " (FAILED, written with --force)");
  std::printf("  views         %zu (%llu of %llu covered pixels matched under t_h)\n",
              r.views.size(), (unsigned long long)r.matchedPixels,
              (unsigned long long)r.coveredPixels);
  std::printf(
      "  points        %llu, over-exposed %llu: expanded %llu, unseen %llu, matches rejected "
      "%llu\n",
      (unsigned long long)r.points, (unsigned long long)r.overexposed,
      (unsigned long long)r.projected, (unsigned long long)r.unseen,
      (unsigned long long)r.rejectedMatches);
  std::printf(
      "  in-fill       %llu points in %llu chunk(s) (largest %llu points), %llu island(s) of "
      "%llu points "
      "kept LDR\n",
      (unsigned long long)r.infilled, (unsigned long long)r.chunks,
      (unsigned long long)r.chunkMaxPoints, (unsigned long long)r.islands,
      (unsigned long long)r.islandPoints);
  std::printf(
      "  largest value %.4g (1 = the scan's clipping; bound %.4g, %llu channel values clamped "
      "to it)\n",
      r.maxValue, c.bound, (unsigned long long)r.boundedValues);
  std::printf("  seconds      ");
  for (auto& [k, v] : r.seconds.items()) std::printf(" %s %.2f", k.c_str(), v.get<double>());
  std::printf("\n  peak memory   %s\n", humanBytes(double(r.peakRssBytes)).c_str());
}

}  // namespace

void addExpandHdr(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("expand-hdr", kExpandHdrHelp);
  auto dir = std::make_shared<std::string>();
  auto photo = std::make_shared<std::string>();
  auto viewsFile = std::make_shared<std::string>();
  auto mode = std::make_shared<std::string>("rgb");
  auto debug = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto quiet = std::make_shared<bool>(false);
  auto o = std::make_shared<gi::hdr::ExpandOptions>();
  cmd->add_option("octree", *dir, "Octree folder (its points need rgb colour)")->required();
  cmd->add_option("--photo", *photo, "HDR photograph of part of the scene, linear (.exr or .hdr)")
      ->required();
  auto* views =
      cmd->add_option("--views", *viewsFile,
                      "Views to render the scan from (cams.json: docs/HDR.md); default: automatic");
  cmd->add_option("--auto-views", o->autoViews,
                  "Cube maps placed automatically to see the over-exposed points (when no --views)")
      ->capture_default_str()
      ->check(CLI::Range(1, 64))
      ->excludes(views);
  auto photoViewFile = std::make_shared<std::string>();
  cmd->add_option(
      "--photo-view", *photoViewFile,
      "The photograph's camera, when registered with the scan (a cams.json with one view): the "
      "scan is also rendered from it (at the photograph's size), matched from the identity, and "
      "the points it matched take "
      "their colour from it alone; the other views (--views or --auto-views) reach the rest");
  auto photoMaskFile = std::make_shared<std::string>();
  cmd->add_option(
         "--photo-mask", *photoMaskFile,
         "A mask drawn on the photograph, at its size (.png, .exr or .hdr): white (above half) "
         "where it shows the scanned scene, black where it shows what the scan lacks (sky, "
         "lamps or buildings beyond the scan, people). Masked-out pixels count for nothing: "
         "not in the exposure's estimate or checks, not in the bound, and no match lands on "
         "them. Registered or not")
      ->check(CLI::ExistingFile);
  cmd->add_option("--photo-search", o->photoSearchRadius,
                  "How far (pixels) matches of the --photo-view rendering may move from the "
                  "identity; 0: anywhere")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  cmd->add_option("--face-size", o->faceSize, "Face size of automatic cube maps (pixels)")
      ->capture_default_str()
      ->check(CLI::Range(32, 4096));
  cmd->add_option(
         "--mode", *mode,
         "rgb: the photograph's colour (PMATCHRGB); luminance: its luminance only, the scan's "
         "chromaticity kept (PMATCHLUM)")
      ->capture_default_str()
      ->check(CLI::IsMember({"rgb", "luminance"}));
  cmd->add_option("--threshold", o->overexposed,
                  "t_l: LDR luminance (linear) above which a point is expanded")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--max-ssd", o->maxSsd,
                  "t_h: matches whose 7x7 patch SSD exceeds this are rejected")
      ->capture_default_str();
  cmd->add_option("--neighbours", o->neighbours, "k of the in-fill's nearest-neighbour graph")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  cmd->add_option("--chunk-points", o->chunkPoints, "Points per in-fill chunk (bounds memory)")
      ->capture_default_str();
  auto forcedExposure = std::make_shared<double>(0.0);
  auto* exposureOpt = cmd->add_option("--exposure", *forcedExposure,
                                      "Force the photograph's exposure, in stops (log2 of the "
                                      "factor that takes the photograph's values to "
                                      "the scan's, 1 being the scan's clipping): no estimate; the "
                                      "exposure's checks are recorded but do not stop (the "
                                      "matched share still does)");
  cmd->add_flag(
      "--force", o->force,
      "Write the layer even when the exposure or match checks fail (they become warnings, "
      "recorded in the layer's build notes)");
  cmd->add_option(
         "--max-spread", o->maxSpreadStops,
         "Largest robust spread (stops) of the log ratios between scan and photograph accepted")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 20.0));
  cmd->add_option("--min-matched", o->minMatchedShare,
                  "Smallest share of the over-exposed points that must take a matched value")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--layer", o->layerName, "Name of the colour layer to write")
      ->capture_default_str();
  cmd->add_option("--scratch", o->scratchDir,
                  "Folder of the scratch file (16 bytes a point; default: the octree's)");
  cmd->add_option("--debug", *debug, "Write the renderings, expanded renderings and views here");
  cmd->add_flag("--json", *json, "Print the report as JSON");
  cmd->add_flag("-q,--quiet", *quiet, "No progress output");
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "expand-hdr");
    if (!viewsFile->empty()) o->views = gi::hdr::readViews(*viewsFile);
    if (!photoViewFile->empty()) {
      const auto v = gi::hdr::readViews(*photoViewFile);
      if (v.size() != 1)
        throw Error(*photoViewFile, "",
                    "--photo-view: expected one view, found " + std::to_string(v.size()));
      o->photoView = v.front();
    }
    const gi::HdrImage image = gi::readHdrImage(*photo);
    if (!photoMaskFile->empty()) o->photoMask = readPhotoMask(*photoMaskFile, image);
    if (exposureOpt->count() > 0) {
      if (!std::isfinite(*forcedExposure) || std::fabs(*forcedExposure) > 64)
        throw Error("", "--exposure",
                    "expected stops between -64 and 64 (log2 of the exposure), got " +
                        std::to_string(*forcedExposure));
      o->log2Exposure = *forcedExposure;
    }
    o->mode = *mode == "rgb" ? gi::hdr::ExpansionMode::Rgb : gi::hdr::ExpansionMode::Luminance;
    o->debugDir = *debug;
    o->commandLine = {{"photo", *photo},
                      {"mode", *mode},
                      {"views", viewsFile->empty() ? "auto" : *viewsFile},
                      {"photo_view", *photoViewFile},
                      {"photo_mask", *photoMaskFile},
                      {"force", o->force}};
    if (o->log2Exposure) o->commandLine["exposure"] = *o->log2Exposure;
    auto mutex = std::make_shared<std::mutex>();
    auto last = std::make_shared<std::pair<std::string, int>>("", -1);
    if (!*quiet)
      o->progress = [mutex, last](const std::string& stage, double f) {
        std::lock_guard<std::mutex> lock(*mutex);
        const int pct = int(f * 100);
        if (stage == last->first && pct / 10 == last->second / 10 && pct < 100) return;
        *last = {stage, pct};
        std::fprintf(stderr, "expand-hdr: %-16s %3d%%\n", stage.c_str(), pct);
      };
    const gi::hdr::ExpandReport r = gi::hdr::expandHdr(*dir, image, *o);
    for (const auto& w : r.warnings)
      std::fprintf(stderr, "expand-hdr: warning (--force): %s\n", w.c_str());
    if (*json) {
      std::printf("%s\n", r.toJson().dump(2).c_str());
    } else {
      printReport(r, *dir, *mode, *o);
    }
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
