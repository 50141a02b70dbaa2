// The out-of-core nested-octree builder (`nestlight convert`).
//
// Phases, as in Potree 2 (Schütz, Ohrhallinger, Wimmer 2020) and DESIGN.md: count points on a
// coarse grid; distribute them into chunk files, each a node of the octree small enough to
// index in memory; index each chunk into its subtree; merge the levels above the chunks.
// The phases exchange only files. Sampling is bottom-up everywhere (a node draws its points from
// its children's), so each node depends only on the points of its own subtree: the chunked
// build is byte-identical to an in-memory build, and independent of input order.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/converters/communicator.h"
#include "nestlight/converters/progress.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/octree/process_memory.h"  // peakRssBytes, which BuildReport carries

namespace nestlight {

enum class Sampling { Poisson, Grid };
enum class NormalOrientation { Outward, Inward, Up };

struct BuildOptions {
  std::filesystem::path output;
  uint64_t memoryBytes = uint64_t(1) << 30;  // --memory: bound on the builder's own memory
  unsigned threads = 0;                      // 0: all cores
  Sampling sampling = Sampling::Poisson;
  Codec codec = Codec::Zstd;
  double precision = 0;  // world units; 0: from the inputs (LAS scale) or 1 mm
  bool dedup = false;    // merge exact duplicates (position and attributes)
  bool estimateNormals = false;
  unsigned normalNeighbours = 16;
  // Neighbours further than this (world units) from the point along a first fit's normal are
  // left out of its plane fit (Rohmer et al. 2017, section 5: 0.1 m); 0: every neighbour.
  double normalDepthLimit = 0.1;
  NormalOrientation normalOrientation = NormalOrientation::Outward;
  bool overwrite = false;
  uint32_t maxNodePoints = 20000;  // leaf size and cap on an inner node's sample
  bool inMemory = false;           // one chunk: the reference the chunked build must equal
  ProgressMode progress = ProgressMode::Auto;
  nlohmann::json commandLine;  // recorded in metadata.build
  // Where chunk files and other temporary data go (a node-local disk); empty: beside the output,
  // in its staging folder. A conversion's own subfolder there is removed at the end, and a killed
  // one's by the next run into the same output.
  std::filesystem::path scratch;
  // A conversion spread over the processes of a job (convert --mpi; nestlight/converters/
  // communicator.h): every rank calls buildOctree with the same inputs and options. Null or a job
  // of one: this process converts alone. See docs/DISTRIBUTED.md.
  Communicator* comm = nullptr;
};

struct BuildReport {
  Metadata metadata;
  double seconds = 0;
  double pointsPerSecond = 0;
  uint64_t peakRssBytes = 0;
  uint64_t chunks = 0;
  nlohmann::json phases;              // seconds per phase
  std::vector<std::string> warnings;  // about the build itself (sources' warnings are in metadata)
  // A job of several ranks: per rank (rank 0's report; the others hold their own entry only) its
  // input bytes, points indexed, bytes sent to other ranks, peak memory and phases.
  nlohmann::json ranks;
};

// Builds the octree of every point of `sources`. Throws nestlight::Error on bad input.
BuildReport buildOctree(std::vector<std::unique_ptr<PointReader>> sources,
                        const BuildOptions& options);

}  // namespace nestlight
