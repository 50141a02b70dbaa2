// `nestlight bench diffrender`: options for bench::runBenchDiffrender
// (nestlight/bench/bench_diffrender.h).
#include <cmath>
#include <cstdio>
#include <sstream>

#include "cli.h"
#include "nestlight/bench/bench_diffrender.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace {

std::vector<std::string> splitNames(const std::string& text) {
  std::vector<std::string> v;
  std::stringstream ss(text);
  for (std::string s; std::getline(ss, s, ',');)
    if (!s.empty()) v.push_back(s);
  return v;
}

std::vector<int> countList(const std::string& text, const std::string& option) {
  std::vector<int> v;
  for (double x : parseNumberList(text, option)) {
    if (!(x >= 1 && x <= 1024) || x != std::floor(x)) {
      char text[48];
      std::snprintf(text, sizeof text, "%g", x);
      throw Error(option, "", std::string("'") + text + "' is not an integer from 1 to 1024");
    }
    v.push_back(int(x));
  }
  return v;
}

const char* kHelp =
    "The evaluation of differential rendering (Rohmer, Jendersie and Grosch 2017, section 8) on a\n"
    "scene with inserted meshes and a capture layer (make-scene diffrender). The ground truth is\n"
    "bench gi's: R1 and R0, the reference with and without the inserted meshes (cached in the\n"
    "output folder), their difference, the capture, the scan's albedo and diffrender's mask. Each\n"
    "configuration of diffrender (gi.parameters overridden) is set up (made, one untimed frame),\n"
    "timed over --runs frames (medians of the frame and of every pass, synchronised wall times\n"
    "and GPU timer queries) and rendered once more with its AOVs for the errors (relative L2).\n"
    "Tables (--tables), printed and in OUT/bench_diffrender.md, each also a CSV, all in JSON:\n"
    "  presets      Tables 2/3: per query x preset the passes' times, the frame's, and the "
    "errors:\n"
    "               composite vs R1, dL vs R1-R0 (scan blocks), object pixels vs R1, rho vs the\n"
    "               albedo, rho clamped and DIT's counters\n"
    "  cache        Table 4: DIT at med, --samples N x --cache (cache <= N), the shade (dL) "
    "pass's\n"
    "               time and the dL and object errors, with and without self_shadow\n"
    "  self-shadow  Fig. 9: object-pixel error per query without (low) and with (med) self-shadow\n"
    "  material     Fig. 10: rho and |dL| images (OUT/images, EXR and PNG) and the mean rho on "
    "the\n"
    "               floor against the true albedo (target: within 5%)\n"
    "  equal-time   Fig. 11: dL error over --samples per --sweep-queries query (med, cache\n"
    "               --sweep-cache or N), and at equal time: each query's largest N whose median\n"
    "               frame time is within --equal-time-ms (default DIT med's); says whether DIT\n"
    "               and VCT beat EM\n"
    "Example: nestlight make-scene diffrender -o dr --width 160 --height 120 --bake-spp 16\n"
    "         nestlight bench diffrender dr/scene.json --queries em,dit,vct --runs 3";

}  // namespace

void addBenchDiffrender(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand("diffrender", kHelp);
  auto o = std::make_shared<bench::BenchDiffrenderOptions>();
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto queries = std::make_shared<std::string>("em,dit,vct,exact");
  auto presets = std::make_shared<std::string>("low,med,high");
  auto samples = std::make_shared<std::string>("8,16,32,64,128");
  auto caches = std::make_shared<std::string>("8,16,32");
  auto sweepQueries = std::make_shared<std::string>();
  auto tables = std::make_shared<std::string>("presets,cache,self-shadow,material,equal-time");
  auto budget = std::make_shared<double>(0);
  cmd->add_option("scene", *scene, "Scene file (.json) with inserted meshes and a capture layer")
      ->required();
  cmd->add_option("-o,--out", *out, "Output folder (default: bench-diffrender beside the scene)");
  cmd->add_option("--queries", *queries, "Queries, comma-separated: em, dit, vct, exact")
      ->capture_default_str();
  cmd->add_option("--presets", *presets, "Presets of Tables 2/3, comma-separated: low, med, high")
      ->capture_default_str();
  cmd->add_option("--samples", *samples,
                  "N (samples per scan pixel) of the cache and equal-time sweeps, comma-separated")
      ->capture_default_str();
  cmd->add_option("--cache", *caches, "Cache sizes of Table 4's sweep (cache <= N only)")
      ->capture_default_str();
  cmd->add_option("--sweep-queries", *sweepQueries,
                  "Queries of the equal-time sweep, comma-separated (default: --queries without "
                  "exact, whose frames take seconds on a CPU rasteriser)");
  cmd->add_option("--sweep-cache", o->sweepCache,
                  "Cache of the equal-time sweep, shrunk to N where N is smaller (8: the med "
                  "preset's, so its N = 16 is DIT med)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--tables", *tables,
                  "Tables to make, comma-separated: presets, cache, self-shadow, material, "
                  "equal-time")
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "Timed frames per configuration after its set-up frame")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->add_option("--equal-time-ms", *budget,
                  "Fig. 11's budget, ms of frame time (default: DIT med's median frame time)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--reference-error", o->referenceError,
                  "Relative error R1 and R0 are rendered to (cached in the output folder)")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--reference-time-limit", o->referenceTimeLimit,
                  "Seconds each reference may take at most")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e7));
  cmd->add_option("--reference-spp", o->referenceSpp, "Samples per pixel of a reference at most")
      ->capture_default_str()
      ->check(CLI::Range(2, 1 << 24));
  cmd->add_flag("--force-reference", o->forceReference,
                "Render the references again even when cached ones match");
  cmd->add_option("--width", o->width, "Override the scene camera's width")
      ->check(CLI::Range(1, 16384));
  cmd->add_option("--height", o->height, "Override the scene camera's height")
      ->check(CLI::Range(1, 16384));
  cmd->callback([=, &exitCode]() {
    bench::BenchDiffrenderOptions opt = *o;
    opt.scene = *scene;
    opt.out = *out;
    opt.device = cpuName();
    opt.queries = splitNames(*queries);
    opt.presets = splitNames(*presets);
    opt.tables = splitNames(*tables);
    opt.sweepQueries = splitNames(*sweepQueries);
    opt.samples = countList(*samples, "--samples");
    opt.caches = countList(*caches, "--cache");
    if (*budget > 0) opt.equalTimeMs = *budget;
    bench::runBenchDiffrender(opt, stdout);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
