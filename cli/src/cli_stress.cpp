// `nestlight stress`: flies random and fast camera paths (teleports, fast flights, orbits, stops)
// over an octree through the streaming scheduler with a memory store and small budgets, checks
// every frame (budget held at every upload, no reader call on the render thread, parents drawn
// before children, every request completed or cancelled, the cut complete soon after each stop)
// and exits non-zero on any violation.
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/stress.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void addStress(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("stress",
                                 "Stress-test the streaming scheduler: random teleports, fast "
                                 "flights, orbits and stops over an\n"
                                 "octree with a memory store and small budgets; checks every frame "
                                 "and exits 2 on a violation");
  auto dir = std::make_shared<std::string>();
  auto opt = std::make_shared<streaming::StressOptions>();
  auto text =
      std::make_shared<std::array<std::string, 3>>(std::array<std::string, 3>{"1M", "24M", "2M"});
  auto json = std::make_shared<std::string>();
  auto generate = std::make_shared<std::string>();
  auto work = std::make_shared<std::string>();
  auto fixed = std::make_shared<bool>(false);
  auto quiet = std::make_shared<bool>(false);
  cmd->add_option("octree", *dir, "Octree folder (or --generate)");
  cmd->add_option("--frames", opt->frames, "Camera frames (the final stop and drain come on top)")
      ->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Seed of the camera paths and budget changes")
      ->capture_default_str();
  cmd->add_option("--point-budget", (*text)[0], "Points in the cut (accepts 500k, 2M)")
      ->capture_default_str();
  cmd->add_option("--gpu-budget", (*text)[1], "Resident bytes (accepts 64M, 1G)")
      ->capture_default_str();
  cmd->add_option("--upload-budget", (*text)[2], "Upload bytes per frame")->capture_default_str();
  cmd->add_option("--loaders", opt->budgets.loaderThreads, "Loader threads")->capture_default_str();
  cmd->add_option("--spacing-pixels", opt->budgets.spacingPixels,
                  "Screen-space error target (pixels)")
      ->capture_default_str();
  cmd->add_option("--settle-frames", opt->settleFrames,
                  "Frames a stopped camera may wait for the cut to become complete")
      ->capture_default_str();
  cmd->add_option("--frame-ms", opt->frameMs,
                  "Frame period: each update() is followed by a sleep to it (0: none)")
      ->capture_default_str();
  cmd->add_option("--max-update-ms", opt->maxUpdateMs,
                  "An update() longer than this is a violation (0: off)")
      ->capture_default_str();
  cmd->add_flag("--fixed-budgets", *fixed,
                "Keep the budgets (by default they change now and then)");
  cmd->add_option("--json", *json, "Also write the summary as JSON to this file");
  cmd->add_option("--generate", *generate,
                  "Generate and convert a synthetic scan of this many points first");
  cmd->add_option("--dir", *work,
                  "Folder for --generate (default: a temporary folder, removed afterwards)");
  cmd->add_flag("-q,--quiet", *quiet, "No progress lines");
  cmd->callback([=, &exitCode]() {
    streaming::StressOptions o = *opt;
    o.budgets.points = parseCount((*text)[0], "--point-budget");
    o.budgets.gpuBytes = parseBytes((*text)[1]);
    o.budgets.uploadBytesPerFrame = parseBytes((*text)[2]);
    o.varyBudgets = !*fixed;
    if (dir->empty() == generate->empty())
      throw Error("", "", "give an octree folder or --generate N (one of them)");
    fs::path octree = *dir;
    fs::path temp;
    if (!generate->empty()) {
      temp = work->empty()
                 ? fs::temp_directory_path() / ("nestlight-stress-" + std::to_string(::getpid()))
                 : fs::path();
      octree = ensureSyntheticOctree(parseCount(*generate, "--generate"),
                                     work->empty() ? temp : fs::path(*work));
    }
    OctreeReader reader(octree);
    const Metadata& m = reader.metadata();
    std::printf("stress: %s (%s points, %llu nodes), %llu frames, seed %llu\n", octree.c_str(),
                humanCount(double(m.points)).c_str(), (unsigned long long)m.nodes,
                (unsigned long long)o.frames, (unsigned long long)o.seed);
    std::printf(
        "budgets: %s points, %s resident, %s uploads per frame, %d loaders, %g px spacing%s\n",
        humanCount(double(o.budgets.points)).c_str(),
        humanBytes(double(o.budgets.gpuBytes)).c_str(),
        humanBytes(double(o.budgets.uploadBytesPerFrame)).c_str(), o.budgets.loaderThreads,
        o.budgets.spacingPixels, o.varyBudgets ? " (scaled x0.25..x2 at random)" : "");
    std::fflush(stdout);
    if (!*quiet) {
      o.progressEvery = 1000;
      o.progress = [](uint64_t f) {
        std::fprintf(stderr, "  frame %llu\n", (unsigned long long)f);
      };
    }
    const auto t = std::chrono::steady_clock::now();
    const streaming::StressReport r = streaming::runStress(reader, o);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    const auto& tt = r.totals;
    std::printf(
        "frames     %llu in %.1f s, %llu stops: complete after %llu frames (median), %llu (max; "
        "bound %llu)\n",
        (unsigned long long)r.frames, secs, (unsigned long long)r.stops,
        (unsigned long long)r.settleFramesMedian, (unsigned long long)r.settleFramesMax,
        (unsigned long long)o.settleFrames);
    std::printf(
        "update     wall median %.3f ms, p99 %.3f ms, max %.3f ms; CPU median %.3f ms, "
        "p99 %.3f ms, max %.3f ms\n",
        r.updateMsMedian, r.updateMsP99, r.updateMsMax, r.updateCpuMsMedian, r.updateCpuMsP99,
        r.updateCpuMsMax);
    std::printf("reader     calls on the render thread inside update(): %llu\n",
                (unsigned long long)r.renderThreadReaderCalls);
    std::printf(
        "loads      %llu requested, %llu completed, %llu cancelled, %llu failed, %llu discarded; "
        "%s read\n",
        (unsigned long long)tt.requested, (unsigned long long)tt.completed,
        (unsigned long long)tt.cancelled, (unsigned long long)tt.failed,
        (unsigned long long)tt.discarded, humanBytes(double(tt.bytesRead)).c_str());
    std::printf(
        "residency  %llu uploads, %llu evictions, at most %s resident; %llu budget changes\n",
        (unsigned long long)tt.uploaded, (unsigned long long)tt.evicted,
        humanBytes(double(r.maxResidentBytes)).c_str(), (unsigned long long)r.budgetChanges);
    for (const auto& v : r.violations) std::fprintf(stderr, "violation: %s\n", v.c_str());
    if (r.violationCount > r.violations.size())
      std::fprintf(stderr, "violation: ... and %llu more\n",
                   (unsigned long long)(r.violationCount - r.violations.size()));
    std::printf("result     %s\n",
                r.ok() ? "OK: every check held"
                       : ("FAILED: " + std::to_string(r.violationCount) + " violations").c_str());
    if (!json->empty()) {
      nlohmann::json j = r.toJson();
      j["octree"] = octree.string();
      j["points"] = m.points;
      j["nodes"] = m.nodes;
      j["seconds"] = secs;
      j["options"] = {{"frames", o.frames},
                      {"seed", o.seed},
                      {"point_budget", o.budgets.points},
                      {"gpu_budget", o.budgets.gpuBytes},
                      {"upload_budget", o.budgets.uploadBytesPerFrame},
                      {"loaders", o.budgets.loaderThreads},
                      {"spacing_pixels", o.budgets.spacingPixels},
                      {"settle_frames", o.settleFrames},
                      {"frame_ms", o.frameMs},
                      {"vary_budgets", o.varyBudgets}};
      std::ofstream(*json) << j.dump(2) << "\n";
    }
    if (!temp.empty()) {
      std::error_code ec;
      fs::remove_all(temp, ec);
    }
    exitCode = r.ok() ? kExitOk : kExitCheckFailed;
  });
}

}  // namespace nestlight::cli
