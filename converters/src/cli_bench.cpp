// `nestlight bench`: placeholder until the benchmark harness lands.
#include "cli.h"
namespace nestlight::cli {
void addBench(CLI::App& app, int&) { app.add_subcommand("bench", "Benchmarks (see bench/)"); }
}  // namespace nestlight::cli
