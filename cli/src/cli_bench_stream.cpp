// `nestlight bench stream`: options for bench::runStreamBench
// (nestlight/bench/stream_bench.h).
#include <fstream>

#include "cli.h"
#include "nestlight/bench/stream_bench.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

void addBenchStream(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "stream",
      "Streaming scheduler: CPU time per frame with every node resident, time to full detail "
      "after\n"
      "a teleport, bytes read per converged view against the bytes its nodes hold");
  auto dir = std::make_shared<std::string>();
  auto generate = std::make_shared<std::string>();
  auto work = std::make_shared<std::string>("bench-data");
  auto o = std::make_shared<bench::StreamBenchOptions>();
  auto out = std::make_shared<std::string>("bench-stream.json");
  cmd->add_option("octree", *dir, "Octree folder (or --generate)");
  cmd->add_option("--generate", *generate,
                  "Generate and convert a synthetic scan of this many points (e.g. 100M)");
  cmd->add_option("--dir", *work, "Folder for --generate (reused when it holds that octree)")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames timed per camera path with every node resident")
      ->capture_default_str();
  cmd->add_option("--teleports", o->teleports,
                  "Random views for the teleport and bytes-read measures")
      ->capture_default_str();
  cmd->add_option("--frame-ms", o->frameMs, "Frame period while waiting for full detail")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed of the random views")->capture_default_str();
  cmd->add_option("--json", *out, "Where to write the results")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    if (dir->empty() == generate->empty())
      throw Error("", "", "give an octree folder or --generate N (one of them)");
    fs::path octree = *dir;
    if (!generate->empty())
      octree = ensureSyntheticOctree(parseCount(*generate, "--generate"),
                                     fs::path(*work) / ("stream_" + *generate + ".octree"));
    bench::StreamBenchOptions opt = *o;
    opt.device = cpuName();
    const nlohmann::json results = bench::runStreamBench(octree, opt, stdout);
    std::ofstream(*out) << results.dump(2) << "\n";
    std::printf("results written to %s\n", out->c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
