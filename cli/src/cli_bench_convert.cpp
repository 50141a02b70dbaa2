// `nestlight bench` and `nestlight bench convert`: options for bench::runBenchConvert
// (nestlight/bench/bench_convert.h).
#include "cli.h"
#include "nestlight/bench/bench_convert.h"

namespace nestlight::cli {

void addBench(CLI::App& app, int& exitCode) {
  auto* bench = app.add_subcommand(
      "bench",
      "Benchmarks: conversion, LAZ decoding, streaming, point rendering and the GI frame's passes "
      "against\n"
      "size; the GI methods, IBL estimators and HDR expansion against error (docs/PERFORMANCE.md)");
  bench->require_subcommand(1);
  auto* cmd = bench->add_subcommand(
      "convert", "Conversion speed, peak RSS, bytes/point per codec, time to open the root");
  auto sizes = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"20M", "100M"});
  auto o = std::make_shared<bench::BenchConvertOptions>();
  cmd->add_option("--sizes", *sizes, "Point counts of the generated LAS files")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--codecs", o->codecs, "Codecs compared on the first size (one run each)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "Runs per size with zstd (the median is reported)")
      ->capture_default_str();
  cmd->add_option("--dir", o->dir, "Folder for the generated scans and octrees (reused)")
      ->capture_default_str();
  cmd->add_option("--memory", o->memory, "--memory passed to convert")->capture_default_str();
  cmd->add_option("--sampling", o->sampling, "--sampling passed to convert")->capture_default_str();
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->add_option("--mpi", o->mpiRanks,
                  "Rank counts (e.g. 1,2,4): each size as 8 tiles converted by `mpirun -n N "
                  "nestlight convert --mpi` and by one process without MPI; seconds, speed-up, "
                  "bytes exchanged per point, each rank's peak memory and phases "
                  "(docs/DISTRIBUTED.md)")
      ->delimiter(',');
  cmd->callback([=, &exitCode]() {
    o->sizes.clear();
    for (const auto& sz : *sizes) o->sizes.emplace_back(sz, parseCount(sz, "--sizes"));
    bench::runBenchConvert(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
