// `nestlight compare TEST REFERENCE`: how wrong an image is against a reference, as a table or
// JSON, with an optional false-colour error image. The metrics and their conventions live in
// gi/metrics (metrics.h); SSIM is Wang et al., IEEE TIP 13(4), 2004, relative MSE Rousselle et
// al., ACM TOG 30(6), 2011.
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {
namespace {

constexpr const char* kMetricsHelp =
    "Metrics, over pixels finite in both images (t test, r reference, per colour channel):\n"
    "  RMSE                 sqrt(mean (t-r)^2) over pixels and channels, as oiiotool --diff "
    "reports it\n"
    "  mean / max abs       mean and largest |t-r|\n"
    "  relative MSE         mean (t-r)^2 / (r^2 + 0.01); the 0.01 keeps black pixels finite "
    "(Rousselle 2011)\n"
    "  mean relative        mean |t-r| / (|r| + 0.01)\n"
    "  PSNR                 10 log10(peak^2 / MSE) dB; peak = reference max (linear HDR) or 1 "
    "(tone-mapped)\n"
    "  SSIM                 structural similarity (Wang 2004): 11x11 Gaussian window, sigma 1.5, "
    "K1 0.01,\n"
    "                       K2 0.03, mean of R,G,B; dynamic range L = the PSNR peak; 1 is "
    "identical\n"
    "  tone-mapped          both images times 2^exposure, clamped to [0,1], sRGB-encoded, then as "
    "above\n"
    "  non-finite           pixels with NaN or Inf in either image are counted and left out of "
    "every metric\n"
    "Exit status: 0 when the images were compared, 1 on bad input (unreadable file, sizes differ,\n"
    "no pixel finite in both).";

std::string number(double v) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string nonFiniteText(const gi::NonFiniteCount& n) {
  return std::to_string(n.pixels) + " pixels (" + std::to_string(n.nan) + " NaN, " +
         std::to_string(n.inf) + " Inf values)";
}

void printTable(const std::string& testFile, const std::string& referenceFile,
                const gi::ImageComparison& c) {
  std::printf("test        %s  %dx%d\n", testFile.c_str(), c.width, c.height);
  std::printf("reference   %s  %dx%d\n", referenceFile.c_str(), c.width, c.height);
  std::printf("pixels      %llu compared of %llu\n", (unsigned long long)c.compared,
              (unsigned long long)c.pixels);
  const bool anyBad = c.test.pixels || c.reference.pixels;
  std::printf("%snon-finite test %s, reference %s%s\n", anyBad ? "warning: " : "",
              nonFiniteText(c.test).c_str(), nonFiniteText(c.reference).c_str(),
              anyBad ? "; left out of every metric" : "");
  char exposure[32];
  std::snprintf(exposure, sizeof exposure, "%+g EV", c.exposureStops);
  std::printf("\n%-22s %-16s %s\n", "", "linear HDR",
              (std::string("tone-mapped (") + exposure + ")").c_str());
  auto row = [&](const char* name, double linear, double toneMapped) {
    std::printf("%-22s %-16s %s\n", name, number(linear).c_str(), number(toneMapped).c_str());
  };
  const gi::ErrorStats &l = c.linear, &t = c.toneMapped;
  row("RMSE", l.rmse, t.rmse);
  row("mean absolute error", l.meanAbsolute, t.meanAbsolute);
  row("max absolute error", l.maxAbsolute, t.maxAbsolute);
  row("relative MSE", l.relativeMse, t.relativeMse);
  row("mean relative error", l.meanRelative, t.meanRelative);
  row("PSNR (dB)", l.psnr, t.psnr);
  row("SSIM", l.ssim, t.ssim);
  row("peak / SSIM L", l.peak, t.peak);
  std::printf("\ntone map: 2^exposure, clamp to [0,1], sRGB OETF; relative metrics eps = %s\n",
              number(c.relativeEpsilon).c_str());
}

}  // namespace

void addCompare(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("compare",
                                 "Error of an image against a reference: RMSE, relative MSE, PSNR, "
                                 "SSIM on linear HDR and tone-mapped");
  struct Options {
    std::string test, reference, errorImage;
    std::vector<double> errorRange;
    double exposure = 0;
    bool json = false;
    int box = 1;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("test", o->test, "Image to judge: linear .exr or .hdr")->required();
  cmd->add_option("reference", o->reference,
                  "Reference image, e.g. the path tracer's: linear .exr or .hdr, same size")
      ->required();
  cmd->add_option(
      "--error-image", o->errorImage,
      "Write a PNG of per-pixel relative error |t-r|/(|r|+0.01) on a log colour scale (viridis; "
      "magenta = non-finite)");
  cmd->add_option("--error-range", o->errorRange,
                  "Relative errors at the bottom and top of the error image's colour scale "
                  "(default 0.001 1)")
      ->expected(2);
  cmd->add_option("--exposure", o->exposure,
                  "Exposure in stops applied before the tone map (default 0)");
  cmd->add_flag("--json", o->json, "Print JSON instead of a table");
  cmd->add_option(
         "--box", o->box,
         "Compare the means of K x K pixel blocks of both images (separates shading error from "
         "pixel-scale sampling: centre samples against area averages, noisy colours, edges)")
      ->check(CLI::Range(1, 1024));
  cmd->footer(kMetricsHelp);
  cmd->callback([o, &exitCode]() {
    if (!std::isfinite(o->exposure))
      throw Error("", "--exposure", "must be a finite number of stops");
    gi::ErrorImageOptions imageOptions;
    if (!o->errorRange.empty()) {
      imageOptions.minRelative = o->errorRange[0];
      imageOptions.maxRelative = o->errorRange[1];
      if (!(imageOptions.minRelative > 0) ||
          !(imageOptions.maxRelative > imageOptions.minRelative) ||
          !std::isfinite(imageOptions.maxRelative))
        throw Error("", "--error-range",
                    "needs 0 < low < high, got " + number(imageOptions.minRelative) + " " +
                        number(imageOptions.maxRelative));
    }
    gi::HdrImage test = gi::readHdrImage(o->test);
    gi::HdrImage reference = gi::readHdrImage(o->reference);
    if (o->box > 1) {
      gi::checkSameSize(test, reference, o->test, o->reference);
      test = gi::boxFilter(test, o->box);
      reference = gi::boxFilter(reference, o->box);
    }
    gi::CompareOptions options;
    options.exposureStops = o->exposure;
    options.testName = o->test;
    options.referenceName = o->reference;
    const gi::ImageComparison c = gi::compareImages(test, reference, options);
    if (c.compared == 0)
      throw Error(o->test, "",
                  "no pixel is finite in both this image and " + o->reference +
                      " (non-finite: test " + nonFiniteText(c.test) + ", reference " +
                      nonFiniteText(c.reference) + ")");

    nlohmann::json legend;
    if (!o->errorImage.empty())
      legend =
          gi::toJson(gi::writeErrorImage(o->errorImage, test, reference, imageOptions, options));

    if (o->json) {
      nlohmann::json j = gi::toJson(c);
      j["test_file"] = o->test;
      j["reference_file"] = o->reference;
      if (!o->errorImage.empty()) {
        legend["file"] = o->errorImage;
        j["error_image"] = legend;
      }
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      printTable(o->test, o->reference, c);
      double st = 0, sr = 0;
      for (size_t i = 0; i < test.rgb.size(); ++i)
        if (std::isfinite(test.rgb[i]) && std::isfinite(reference.rgb[i]))
          st += test.rgb[i], sr += reference.rgb[i];
      std::printf("mean radiance, test / reference: %.4f\n", sr > 0 ? st / sr : 0.0);
      if (!o->errorImage.empty())
        std::printf("error image %s: %s\n", o->errorImage.c_str(),
                    legend["description"].get<std::string>().c_str());
    }
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
