#include "nestlight/bench/bench_clip.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::bench {
namespace fs = std::filesystem;

void runBenchClip(const BenchClipOptions& o) {
  fs::create_directories(o.dir);
  const fs::path octree =
      o.octree.empty()
          ? ensureSyntheticOctree(o.points, fs::path(o.dir) / ("clip_" + o.pointsName + ".octree"))
          : fs::path(o.octree);
  Metadata m;
  {
    OctreeReader r(octree);
    m = r.metadata();
  }
  const Box3d b = m.bounds;
  const Vec3d c{(b.min.x + b.max.x) / 2, (b.min.y + b.max.y) / 2, (b.min.z + b.max.z) / 2};
  // A box of 0.45 of the bounds on each axis (a tenth of their volume), off the nodes' grid.
  ClipSet box;
  box.volumes.push_back(ClipVolume::box(
      {c.x + 0.013 * (b.max.x - b.min.x), c.y - 0.017 * (b.max.y - b.min.y), c.z},
      {0.45 * (b.max.x - b.min.x), 0.45 * (b.max.y - b.min.y), 0.45 * (b.max.z - b.min.z)}));
  const fs::path clipFile = fs::path(o.dir) / "bench_clip_box.json";
  {
    std::ofstream f(clipFile);
    f << nlohmann::json{{"clipping", box.toJson()}}.dump(1) << "\n";
  }
  // The profile: across the scan through its middle, a corridor of 1/200 of its width.
  const double width = (b.max.x - b.min.x) / 200;
  char line[256];
  std::snprintf(line, sizeof line, "%.6f,%.6f,%.6f,%.6f", b.min.x,
                c.y + 0.003 * (b.max.y - b.min.y), b.max.x, c.y + 0.003 * (b.max.y - b.min.y));
  ClipSet corridor;
  corridor.volumes.push_back(ClipVolume::corridor(
      {{b.min.x, c.y + 0.003 * (b.max.y - b.min.y)}, {b.max.x, c.y + 0.003 * (b.max.y - b.min.y)}},
      width));

  struct Op {
    std::string name;
    std::vector<std::string> args;
    const ClipSet* clip;
  };
  const std::string oct = octree.string(), dir = o.dir;
  char w[64];
  std::snprintf(w, sizeof w, "%.6f", width);
  const std::vector<Op> ops = {
      {"export --clip (box, LAS)",
       {"nestlight", "export", oct, "-o", dir + "/bench_clip.las", "--clip", clipFile.string(),
        "--progress", "quiet"},
       &box},
      {"info --clip (box, count)", {"nestlight", "info", oct, "--clip", clipFile.string()}, &box},
      {"profile (LAS and PNG)",
       {"nestlight", "profile", oct, "--line", line, "--width", w, "-o", dir + "/bench_profile.las",
        "-o", dir + "/bench_profile.png", "--progress", "quiet"},
       &corridor},
  };
  std::printf("bench clip: %s (%llu points, %s payload), %d runs each, device %s\n", oct.c_str(),
              (unsigned long long)m.points, humanBytes(double(m.payloadBytes)).c_str(), o.runs,
              cpuName().c_str());
  nlohmann::json results = nlohmann::json::array();
  std::vector<std::vector<std::string>> rows = {{"operation", "median s", "points read",
                                                 "read points/s", "payload MB/s", "points kept",
                                                 "peak memory"}};
  for (const Op& op : ops) {
    ExportOptions eo;
    eo.clip = op.clip;
    const ExportReport plan = selectOctree(octree, eo);
    const ExportReport kept = countOctree(octree, eo);
    std::vector<double> secs, rss;
    for (int run = 0; run < o.runs; ++run) {
      const ChildRun r = runChild(op.args);
      if (r.status != 0)
        throw Error(op.name + ": nestlight " + op.args[1] + " failed (status " +
                    std::to_string(r.status) + ")");
      secs.push_back(r.seconds);
      rss.push_back(double(r.peakRss));
    }
    const double s = median(secs), peak = *std::max_element(rss.begin(), rss.end());
    // info --clip reads only the nodes the box cuts: the others are counted from the hierarchy.
    const bool counting = op.args[1] == "info";
    const uint64_t read = counting ? kept.pointsRead : plan.pointsRead;
    const uint64_t bytes = counting ? kept.payloadBytes : plan.payloadBytes;
    rows.push_back({op.name, std::to_string(s).substr(0, 6), humanCount(double(read)),
                    humanCount(read / s), std::to_string(int(bytes / s / 1e6)),
                    humanCount(double(kept.points)), humanBytes(peak)});
    results.push_back({{"operation", op.name},
                       {"seconds", secs},
                       {"median_seconds", s},
                       {"points_read", read},
                       {"points_read_per_second", read / s},
                       {"payload_bytes_read", bytes},
                       {"payload_bytes_per_second", bytes / s},
                       {"points_kept", kept.points},
                       {"nodes_read", counting ? kept.nodes - kept.nodesWhole : plan.nodes},
                       {"nodes_whole", plan.nodesWhole},
                       {"nodes_skipped", plan.nodesSkipped},
                       {"peak_rss_bytes", peak}});
  }
  std::printf("%s", alignedTable(rows).c_str());
  std::ofstream(o.out) << nlohmann::json{{"octree", oct},
                                         {"points", m.points},
                                         {"device", cpuName()},
                                         {"runs", o.runs},
                                         {"results", results}}
                              .dump(1)
                       << "\n";
  std::printf("bench clip: wrote %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
