// `nestlight convert` and the helpers shared by the sub-commands.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "nestlight/converters/builder.h"
#ifdef NESTLIGHT_HAVE_MPI
#include "nestlight/converters/mpi.h"
#endif
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

uint64_t parseCount(const std::string& text, const std::string& option) {
  std::string s = text;
  double mult = 1;
  const char c = s.empty() ? 0 : s.back();
  if (c == 'M' || c == 'm')
    mult = 1e6, s.pop_back();
  else if (c == 'G' || c == 'g' || c == 'B' || c == 'b')
    mult = 1e9, s.pop_back();  // B: billion
  else if (c == 'k' || c == 'K')
    mult = 1e3, s.pop_back();
  size_t used = 0;
  double v = -1;
  try {
    v = std::stod(s, &used);
  } catch (...) {
  }
  if (used != s.size() || !(v >= 0) || !(v * mult < 1.8e19))
    throw Error("", "",
                (option.empty() ? "" : option + ": ") + "cannot read '" + text +
                    "' as a count (e.g. 5M, 800k, 1.5G or 1B)");
  return static_cast<uint64_t>(v * mult);
}

uint64_t parseBytes(const std::string& text) {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (...) {
    throw Error("", "", "cannot read '" + text + "' as a size (e.g. 512M, 2G)");
  }
  std::string unit = text.substr(used);
  std::transform(unit.begin(), unit.end(), unit.begin(), ::tolower);
  double mult = 1;
  if (unit == "k" || unit == "kb" || unit == "kib")
    mult = 1024.0;
  else if (unit == "m" || unit == "mb" || unit == "mib")
    mult = 1024.0 * 1024;
  else if (unit == "g" || unit == "gb" || unit == "gib")
    mult = 1024.0 * 1024 * 1024;
  else if (!unit.empty() && unit != "b")
    throw Error("", "", "unknown size unit in '" + text + "'");
  if (!(v > 0)) throw Error("", "", "size must be positive: '" + text + "'");
  return static_cast<uint64_t>(v * mult);
}

std::vector<std::string> expandInputs(const std::vector<std::string>& inputs) {
  static const std::vector<std::string> exts = {".las", ".laz", ".ply", ".pcd",
                                                ".xyz", ".pts", ".txt", ".csv"};
  std::vector<std::string> out;
  for (const auto& in : inputs) {
    requireExists(in);  // names a near file in its folder (a typo)
    if (fs::is_directory(in)) {
      std::vector<std::string> found;
      for (const auto& e : fs::directory_iterator(in)) {
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
        if (e.is_regular_file() && std::find(exts.begin(), exts.end(), ext) != exts.end())
          found.push_back(e.path().string());
      }
      if (found.empty()) throw Error(in, "", "directory holds no point cloud files");
      std::sort(found.begin(), found.end());
      out.insert(out.end(), found.begin(), found.end());
    } else {
      out.push_back(in);
    }
  }
  return out;
}

ProgressMode parseProgress(const std::string& s) {
  if (s == "terminal") return ProgressMode::Terminal;
  if (s == "json") return ProgressMode::Json;
  if (s == "quiet" || s == "none") return ProgressMode::Quiet;
  return ProgressMode::Auto;
}

void printBuildSummary(const BuildReport& r, const fs::path& out) {
  const Metadata& m = r.metadata;
  const Accounting& a = m.accounting;
  std::printf("built %s\n", out.string().c_str());
  std::printf("  points    %llu in, %llu kept, %llu duplicates merged, %llu rejected\n",
              (unsigned long long)a.input, (unsigned long long)a.kept,
              (unsigned long long)a.duplicatesMerged, (unsigned long long)a.rejectedTotal());
  for (auto& [why, n] : a.rejected)
    if (n) std::printf("            rejected %llu: %s\n", (unsigned long long)n, why.c_str());
  for (auto& s : m.sources)
    for (auto& w : s.warnings) std::printf("  warning   %s: %s\n", s.path.c_str(), w.c_str());
  for (auto& w : r.warnings) std::printf("  note      %s\n", w.c_str());
  std::printf("  octree    %llu nodes, depth %u, %s payload (%.2f bytes/point, %s)\n",
              (unsigned long long)m.nodes, m.depth, humanBytes(double(m.payloadBytes)).c_str(),
              m.points ? double(m.payloadBytes) / m.points : 0.0,
              m.build.value("codec", std::string("?")).c_str());
  std::printf("  time      %.2f s, %s points/s, peak RSS %s, %llu chunks\n", r.seconds,
              humanCount(r.pointsPerSecond).c_str(), humanBytes(double(r.peakRssBytes)).c_str(),
              (unsigned long long)r.chunks);
  std::printf("  phases   ");
  for (auto it = r.phases.begin(); it != r.phases.end(); ++it)
    std::printf(" %s %.2f s", it.key().c_str(), it.value().get<double>());
  std::printf("\n");
  for (const auto& k : r.ranks) {
    std::printf("  rank %-4d %s input, %s points indexed, %s sent, peak RSS %s;",
                k["rank"].get<int>(), humanBytes(k["input_bytes"].get<double>()).c_str(),
                humanCount(k["points_indexed"].get<double>()).c_str(),
                humanBytes(k["bytes_sent"].get<double>()).c_str(),
                humanBytes(k["peak_rss_bytes"].get<double>()).c_str());
    for (const auto& [phase, sec] : k["phases"].items())
      std::printf(" %s %.2f s", phase.c_str(), sec.get<double>());
    std::printf("\n");
  }
}

namespace {
void writeBuildReport(const BuildReport& r, const std::string& file) {
  const nlohmann::json j = {{"seconds", r.seconds},
                            {"points_per_second", r.pointsPerSecond},
                            {"peak_rss_bytes", r.peakRssBytes},
                            {"chunks", r.chunks},
                            {"points", r.metadata.points},
                            {"input_points", r.metadata.accounting.input},
                            {"payload_bytes", r.metadata.payloadBytes},
                            {"phases", r.phases},
                            {"ranks", r.ranks}};
  std::ofstream out(file);
  out << j.dump(2) << "\n";
  if (!out) throw Error(file, "", "cannot write the report");
}
}  // namespace

void addConvert(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("convert", "Build a nested octree from scans, in bounded memory");
  cmd->footer(
      "Inputs: LAS 1.0-1.4 (.las), LAZ (.laz, LASzip 1-3, decoded on every core), COPC\n"
      "(.copc.laz), PLY (.ply), PCD (.pcd), text (.xyz .pts .txt .csv; --columns names the\n"
      "columns); a directory stands for the point files in it, sorted by name. Every input\n"
      "point is kept, merged as an exact duplicate (--dedup) or rejected with a reason;\n"
      "`nestlight info` shows the counts. Progress: each phase's share done and rate, and the\n"
      "ETA of the whole conversion (--progress json: one JSON line at a time, for logs).\n"
      "Normals (--estimate-normals) are fitted to the k nearest neighbours by a closed-form plane\n"
      "fit (neighbours more than --normal-depth-limit off a first fit's plane are left out) and\n"
      "oriented away from the scan's centre (outward: objects and buildings seen from\n"
      "outside), towards it (inward: interiors) or upwards (up: terrain).");
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto opt = std::make_shared<BuildOptions>();
  auto out = std::make_shared<std::string>();
  auto memory = std::make_shared<std::string>("1G");
  auto sampling = std::make_shared<std::string>("poisson");
  auto codec = std::make_shared<std::string>("zstd");
  auto orient = std::make_shared<std::string>("outward");
  auto progress = std::make_shared<std::string>("auto");
  auto read = std::make_shared<ReadOptions>();
  cmd->add_option("inputs", *inputs,
                  "Scan files or directories: .las .laz (LAZ, COPC) .ply .pcd .xyz .pts .txt .csv")
      ->required();
  cmd->add_option("-o,--output", *out, "Output octree folder")->required();
  cmd->add_option("--memory", *memory, "Memory budget of the builder (e.g. 512M, 4G)")
      ->capture_default_str();
  cmd->add_option("--threads", opt->threads, "Worker threads (0: all cores)")
      ->capture_default_str();
  cmd->add_option("--sampling", *sampling, "Node sampling: poisson (even) or grid (faster)")
      ->check(CLI::IsMember({"poisson", "grid"}))
      ->capture_default_str();
  cmd->add_option("--codec", *codec, "Payload codec: zstd, raw or draco")
      ->check(CLI::IsMember({"zstd", "raw", "draco"}))
      ->capture_default_str();
  cmd->add_option("--precision", opt->precision,
                  "Position precision in world units (default: the inputs' LAS scale, else 0.001)");
  cmd->add_flag("--dedup", opt->dedup, "Merge exact duplicates (same position and attributes)");
  cmd->add_flag("--estimate-normals", opt->estimateNormals, "Fit normals where the scan has none");
  cmd->add_option("--normal-neighbours", opt->normalNeighbours, "k for normal estimation")
      ->capture_default_str();
  cmd->add_option("--normal-depth-limit", opt->normalDepthLimit,
                  "Normal estimation: neighbours whose depth (along a first fit's normal) differs "
                  "from the point's by more\n"
                  "than this, in the scan's units, are left out of its plane, so a fit does not "
                  "straddle a thin wall or\n"
                  "a step (0: keep all k)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_option("--normal-orientation", *orient, "outward, inward or up")
      ->check(CLI::IsMember({"outward", "inward", "up"}))
      ->capture_default_str();
  cmd->add_option("--max-node-points", opt->maxNodePoints,
                  "Points per node at most (leaves and samples)")
      ->check(CLI::Range(1000u, 1000000u))
      ->capture_default_str();
  cmd->add_flag("--overwrite", opt->overwrite,
                "Replace an existing octree in the output folder. The new one is built beside it "
                "and swapped in\n"
                "only when complete: a failure, a full disk or a kill leaves the old octree (and "
                "its layers) as it was;\n"
                "other files in the folder are kept");
  cmd->add_flag(
      "--lenient", read->lenient,
      "Keep the complete records of files whose header disagrees with their data, and "
      "the intact chunks of a damaged LAZ file (its damaged chunks count as rejected; a damaged "
      "chunk table is read around by finding the chunks one after the other). A LAZ header that "
      "declares fewer points than the chunks hold is a warning either way, and every point is "
      "read");
  cmd->add_option("--columns", read->columns, "Text inputs: column names, e.g. x,y,z,r,g,b");
  cmd->add_flag("--in-memory", opt->inMemory,
                "Index everything as one chunk (reference build; needs RAM)");
  cmd->add_option("--progress", *progress, "auto, terminal, json or quiet")
      ->check(CLI::IsMember({"auto", "terminal", "json", "quiet"}))
      ->capture_default_str();
  cmd->add_option("--scratch", opt->scratch,
                  "Folder for the temporary chunk files (a fast disk of this machine: with --mpi "
                  "each rank's own, so that only the output is written to the shared file system); "
                  "default: inside the output folder");
  auto reportFile = std::make_shared<std::string>();
  cmd->add_option("--report", *reportFile,
                  "Write the conversion's figures as JSON: seconds, points/s, peak memory, chunks, "
                  "phases and, with --mpi, each rank's (for logs and `bench convert --mpi`)");
  auto mpi = std::make_shared<bool>(false);
  cmd->add_flag("--mpi", *mpi,
                "Convert as one rank of an MPI job: `mpirun -n N nestlight convert INPUTS -o OUT "
                "--mpi` (every rank with the same inputs and options; --memory and --threads are "
                "per rank). The octree holds the same points in the same nodes as one process "
                "makes; docs/DISTRIBUTED.md");
  cmd->callback([=, &exitCode]() {
    BuildOptions o = *opt;
    o.output = *out;
    o.memoryBytes = parseBytes(*memory);
    o.sampling = *sampling == "grid" ? Sampling::Grid : Sampling::Poisson;
    o.codec = *parseCodecName(*codec);
    o.normalOrientation = *orient == "up"       ? NormalOrientation::Up
                          : *orient == "inward" ? NormalOrientation::Inward
                                                : NormalOrientation::Outward;
    o.progress = parseProgress(*progress);
    std::vector<std::string> files = expandInputs(*inputs);
    o.commandLine = {
        {"inputs", files}, {"memory", *memory}, {"sampling", *sampling}, {"codec", *codec}};
    std::unique_ptr<Communicator> comm;
    if (*mpi) {
#ifdef NESTLIGHT_HAVE_MPI
      comm = mpiWorld();
      o.comm = comm.get();
      o.commandLine["ranks"] = comm->size();
      if (comm->rank() != 0) o.progress = ProgressMode::Quiet;  // rank 0 reports for the job
#else
      throw Error(
          "--mpi: this nestlight was built without MPI (scripts/setup.sh installs Open MPI; "
          "configure and build again)");
#endif
    }
    try {
      std::vector<std::unique_ptr<PointReader>> readers;
      for (const auto& f : files) readers.push_back(openReader(f, *read));
      BuildReport r = buildOctree(std::move(readers), o);
      if (!comm || comm->rank() == 0) {
        printBuildSummary(r, o.output);
        if (!reportFile->empty()) writeBuildReport(r, *reportFile);
      }
    } catch (const std::exception& e) {
      if (!comm || comm->size() == 1) throw;
      // The other ranks may wait in a collective for this one: the whole job ends here, and the
      // octree is not committed (a rerun removes what is left).
      std::fprintf(stderr,
                   "nestlight convert --mpi: rank %d of %d: %s\nnestlight convert --mpi: ending "
                   "the job; no octree was committed to %s\n",
                   comm->rank(), comm->size(), e.what(), o.output.c_str());
      comm->abort(1);
    }
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
