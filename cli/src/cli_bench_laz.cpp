// `nestlight bench laz`: options for bench::runBenchLaz (nestlight/bench/bench_laz.h).
#include "cli.h"
#include "nestlight/bench/bench_laz.h"

namespace nestlight::cli {

void addBenchLaz(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "laz", "LAZ decoding speed (one core, all cores) and conversion from LAZ against LAS");
  auto o = std::make_shared<bench::BenchLazOptions>();
  cmd->add_option("files", o->files,
                  "LAZ files whose decoding is measured as well (e.g. real scans)");
  cmd->add_option("--points", o->pointsName,
                  "Points of the generated scan, written as LAS and as LAZ (0: no generated scan "
                  "and no conversion, only the files given)")
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "Runs of each measurement (the median is reported)")
      ->capture_default_str();
  cmd->add_option("--dir", o->dir, "Folder for the generated scans and octrees (reused)")
      ->capture_default_str();
  cmd->add_option("--memory", o->memory, "--memory passed to convert")->capture_default_str();
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->callback([o, &exitCode]() {
    o->points = parseCount(o->pointsName, "--points");
    bench::runBenchLaz(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
