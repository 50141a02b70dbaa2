// `nestlight colour-match`: a photograph brought into the scan's colour space by colour
// compensation (Rohmer et al., "Natural Environment Illumination: Coherent Interactive Augmented
// Reality for Mobile and non-Mobile Devices", 2017, section 4), and composites made in the scan's
// space brought back into the photograph's.
#include <cstdio>

#include "cli.h"
#include "nestlight/gi/hdr/colour_compensation.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void addColourMatch(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "colour-match",
      "Bring a photograph into a scan's colour space (Rohmer et al. 2017, section 4): renders the "
      "scan\n"
      "from the photograph's view, selects pixel pairs that show the same surface (no saturation, "
      "no\n"
      "strong gradient, similar hue and saturation), fits the regularised 3x3 linear map in linear "
      "RGB\n"
      "(gamma 2.2) and writes the photograph through it; --composite brings an image made in the\n"
      "scan's space (a render with inserted objects) back into the photograph's with the inverse.\n"
      "Example: nestlight colour-match scan.octree --photo p.png --views cam.json -o p_scan.exr\n"
      "Exits 2 when the fit is unusable (the identity map is kept and written).");
  auto dir = std::make_shared<std::string>();
  auto photo = std::make_shared<std::string>();
  auto views = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto composite = std::make_shared<std::string>();
  auto compositeOut = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  auto o = std::make_shared<gi::hdr::ColourCompensationOptions>();
  cmd->add_option("octree", *dir, "Octree folder (with rgb colour)")->required();
  cmd->add_option("--photo", *photo, "The photograph: .png (display values) or .exr/.hdr (linear)")
      ->required();
  cmd->add_option("--views", *views,
                  "The photograph's camera (cams.json: docs/HDR.md; the first view)")
      ->required();
  cmd->add_option("-o,--output", *out, "The photograph in the scan's colour space (linear EXR)")
      ->required();
  cmd->add_option("--composite", *composite,
                  "An image in the scan's colour space (linear EXR) to bring back");
  cmd->add_option("--composite-output", *compositeOut,
                  "Where to write it in the photograph's colour space");
  cmd->add_option("--regularisation", o->regularisation,
                  "gamma of eq. 2: the pull towards the per-channel scale")
      ->capture_default_str();
  cmd->add_option("--min-pairs", o->minPairs, "Below this many pairs the per-channel scale is used")
      ->capture_default_str();
  cmd->add_flag("--json", *json, "Print the matrices and pair statistics as JSON");
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "colour-match");
    if (composite->empty() != compositeOut->empty())
      throw Error("", "", "--composite and --composite-output go together");
    const bool linearPhoto = fs::path(*photo).extension() != ".png";
    gi::HdrImage camera = linearPhoto ? gi::readHdrImage(*photo) : gi::readPng(*photo);
    std::vector<gi::hdr::View> v = gi::hdr::readViews(*views);
    gi::hdr::View view = v.front();
    // The rendering takes the photograph's size: its pixels pair with the photograph's.
    view.width = camera.width;
    view.height = camera.height;
    OctreeReader reader(*dir);
    gi::hdr::ScanAccess scan(reader);
    const auto rendering = gi::hdr::renderViews(scan, {view}, gi::hdr::Payload::Display8);
    gi::HdrImage reference = rendering[0].image();
    gi::hdr::ColourCompensationOptions opt = *o;
    if (linearPhoto) {
      opt.inputsLinear = true;
      reference = gi::hdr::linearFromDisplay(reference, opt.gamma);
    }
    const gi::hdr::ColourCompensation c =
        gi::hdr::estimateColourCompensation(camera, reference, rendering[0].coverage(), opt);
    const gi::HdrImage cameraLinear =
        linearPhoto ? camera : gi::hdr::linearFromDisplay(camera, opt.gamma);
    gi::writeExr(*out, gi::hdr::toReferenceSpace(cameraLinear, c),
                 {{"nestlight:colour_space", "scan (" + *dir + ")"}});
    if (!composite->empty())
      gi::writeExr(*compositeOut, gi::hdr::toCameraSpace(gi::readHdrImage(*composite), c),
                   {{"nestlight:colour_space", "photograph (" + *photo + ")"}});
    auto matrix = [](const Eigen::Matrix3d& m) {
      nlohmann::json rows = nlohmann::json::array();
      for (int r = 0; r < 3; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2)});
      return rows;
    };
    const auto& s = c.statistics;
    const nlohmann::json report = {{"matrix", matrix(c.matrix)},
                                   {"inverse", matrix(c.inverse)},
                                   {"approximation", matrix(c.approximation)},
                                   {"approximated", c.approximated},
                                   {"usable", c.usable},
                                   {"condition_number", c.conditionNumber},
                                   {"pairs",
                                    {{"pixels", s.pixels},
                                     {"accepted", s.accepted},
                                     {"saturated", s.saturated},
                                     {"no_data", s.noData},
                                     {"gradient", s.gradient},
                                     {"hs_distance", s.hsDistance},
                                     {"hsv_distance", s.hsvDistance},
                                     {"non_finite", s.nonFinite}}}};
    if (*json) {
      std::printf("%s\n", report.dump(2).c_str());
    } else {
      std::printf(
          "colour-match: %llu of %llu pixel pairs accepted (saturated %llu, no scan data %llu, "
          "gradient %llu, "
          "hue/saturation %llu)\n",
          (unsigned long long)s.accepted, (unsigned long long)s.pixels,
          (unsigned long long)s.saturated, (unsigned long long)s.noData,
          (unsigned long long)s.gradient, (unsigned long long)s.hsDistance);
      std::printf("  %s, condition number %.3g\n",
                  !c.usable ? "unusable: identity kept"
                            : (c.approximated ? "per-channel scale (too few pairs for the 3x3 map)"
                                              : "3x3 map"),
                  c.conditionNumber);
      for (int r = 0; r < 3; ++r)
        std::printf("  [%8.4f %8.4f %8.4f]\n", c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2));
      std::printf("  wrote %s%s%s\n", out->c_str(), composite->empty() ? "" : " and ",
                  compositeOut->c_str());
    }
    exitCode = c.usable ? kExitOk : kExitCheckFailed;
  });
}

}  // namespace nestlight::cli
