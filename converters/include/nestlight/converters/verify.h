// `nestlight verify`: checks an octree folder completely.
//
// Structure (metadata fields, file sizes, hierarchy chunks and their checksums, parent/child
// consistency), every payload's checksum and decoding, every point inside its node's cube, and
// the point accounting (input = kept + merged + rejected; kept = points stored = sum over nodes).
// Attribute layers (the HDR colour): the file's size and index checksum, one entry per node with
// its point count, every payload's checksum and decoding, every value finite and non-negative.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nestlight {

struct VerifyReport {
  std::vector<std::string> failures;  // empty: the octree is sound
  uint64_t nodes = 0;
  uint64_t points = 0;
  uint64_t payloadBytes = 0;
  uint64_t layers = 0;             // attribute layers checked (every node's colours)
  std::vector<std::string> notes;  // not failures: files a killed layer write left behind
  bool ok() const { return failures.empty(); }
};

// Never throws for a damaged octree: every problem becomes a failure line.
VerifyReport verifyOctree(const std::filesystem::path& dir, unsigned maxFailures = 50);

}  // namespace nestlight
