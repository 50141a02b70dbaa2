// Out-of-core nested-octree builder.
//
// Structure after Potree 2 (Schütz, Ohrhallinger, Wimmer, "Fast Out-of-Core Octree Generation for
// Massive Point Clouds", 2020): counting on a coarse grid, distribution into chunk files, indexing
// of each chunk, merging of the levels above. The nested octree itself is the one of Instant
// Points (Wimmer and Scheiblauer 2006), as used by Preiner (seed 004, section 3): each node holds a
// spatially even subsample of its subtree and passes the rest on to its children.
//
// Sampling is bottom-up: a leaf holds all its points; an inner node selects its sample from the
// union of its children's current samples, which then lose the selected points. A node's content
// is therefore a function of its subtree's points alone, so that chunking (and the memory budget
// that decides it) never changes the result, and points are processed in a total order (Morton
// order of position, then attribute bytes) so that input order never does either.
#include "nestlight/converters/builder.h"

#include <tbb/global_control.h>
#include <unistd.h>

#include <cstdio>

#include "builder_passes.h"
#include "nestlight/octree/staged_directory.h"

namespace nestlight {

namespace build_passes {

Builder::Builder(std::vector<std::unique_ptr<PointReader>> sources, const BuildOptions& o,
                 bool measureBounds)
    : opt_(o), progress_(o.progress), measureBounds_(measureBounds) {
  for (auto& r : sources) {
    SourceState s;
    s.reader = std::move(r);
    sources_.push_back(std::move(s));
  }
}

std::vector<std::unique_ptr<PointReader>> Builder::takeSources() {
  std::vector<std::unique_ptr<PointReader>> out;
  for (auto& s : sources_) out.push_back(std::move(s.reader));
  return out;
}

BuildReport Builder::run() {
  auto t0 = Clock::now();
  BuildReport report;
  unsigned threads =
      opt_.threads ? opt_.threads : std::max(1u, std::thread::hardware_concurrency());
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  threads_ = threads;

  comm_ = opt_.comm;
  if (distributed()) dealSources();
  // The phases with progress, and the share of the time each takes (measured: see
  // kPhaseShares), for an ETA across them; "bounds" runs only where a header declares none.
  progress_.plan(kPhaseShares);
  planLayout();
  planQuantisation(report);
  // Built beside the output and swapped in at the end: a failed, full-disk or killed run leaves
  // an existing octree (and its layers) as it was. In a job, rank 0 stages it and commits it once
  // every rank has written its part.
  if (fs::exists(opt_.output / "metadata.json") && !opt_.overwrite)
    throw Error(opt_.output.string(), "",
                "already holds an octree; pass --overwrite to replace it");
  std::optional<StagedDirectory> staged;
  fs::path stagedPath;
  if (rank() == 0) {
    staged.emplace(opt_.output, isOctreeFileName);
    for (const fs::path& p : staged->staleRemoved())
      report.warnings.push_back("removed " + p.string() + ", left by a conversion that was killed");
    stagedPath = staged->path();
  }
  if (distributed()) {
    const std::string p = stagedPath.string();
    const auto all = comm_->allgather(std::vector<uint8_t>(p.begin(), p.end()));
    stagedPath = std::string(all[0].begin(), all[0].end());
  }
  tmp_ = scratchFolder(opt_, stagedPath, rank(), distributed());
  std::error_code ec;
  fs::remove_all(tmp_, ec);  // a killed run's, in a scratch folder outside the output
  fs::create_directories(tmp_);
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(p, ec);
    }
  } cleanup{tmp_};
  // A rank writes its nodes into its own part, in its scratch folder, assembled at the end.
  writer_ = std::make_unique<OctreeWriter>(distributed() ? tmp_ / "part" : stagedPath, layout_,
                                           opt_.codec, true);
  auto anyOutsideCube = [&] {
    return distributed() ? comm_->any(outsideCube_.load()) : outsideCube_.load();
  };

  auto t = Clock::now();
  countPass();
  if (anyOutsideCube()) throw OutsideCube{};
  if (distributed()) assignChunks();
  report.phases["count"] = seconds(t);
  t = Clock::now();
  distributePass();
  if (anyOutsideCube()) throw OutsideCube{};
  report.phases["distribute"] = seconds(t);
  t = Clock::now();
  splitOversizedChunks();
  indexChunks();
  report.phases["index"] = seconds(t);
  t = Clock::now();
  mergeTop();
  report.phases["merge"] = seconds(t);

  if (distributed()) reduceTotals();
  finishMetadata();
  t = Clock::now();
  if (distributed()) {
    assembleOutput(stagedPath);
  } else {
    writer_->finish(meta_);
  }
  writer_.reset();
  fs::remove_all(tmp_);
  if (staged) staged->commit();
  // The others return once the octree is in place: an exit code of 0 means it is there.
  if (distributed()) comm_->barrier();
  report.phases["write"] = seconds(t);
  report.seconds = seconds(t0);
  report.chunks = distributed() ? chunksTotal_ : chunks_.size();
  // Points read, not declared: a lenient conversion's unreadable points took no time.
  uint64_t read = 0;
  for (const auto& src : sources_) read += src.read;
  report.pointsPerSecond = report.seconds > 0 ? double(read) / report.seconds : 0;
  report.peakRssBytes = peakRssBytes();
  report.metadata = meta_;
  if (distributed()) report.ranks = gatherRankReports(report);
  return report;
}

}  // namespace build_passes

using build_passes::Builder;
using build_passes::OutsideCube;

BuildReport buildOctree(std::vector<std::unique_ptr<PointReader>> sources,
                        const BuildOptions& options) {
  Builder b(std::move(sources), options, false);
  try {
    return b.run();
  } catch (const OutsideCube&) {
    // A header declared bounds its points overstep by more than rounding: measure them instead.
  }
  Builder measured(b.takeSources(), options, true);
  BuildReport r = measured.run();
  r.warnings.push_back(
      "points lie far outside the bounds a header declares: the extent was measured from the "
      "points, which took one more reading of the input");
  return r;
}

}  // namespace nestlight
