// The builder as a job of several ranks, the ranks threads of this process (threadGroup): the
// same code `convert --mpi` runs, here under the sanitizers too. Any number of ranks builds the
// octree one process builds (same nodes, same points, same accounting), including with ranks
// that read nothing, with no point at all, and when a lying header makes every rank start over.
#include <gtest/gtest.h>

#include <thread>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/communicator.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

namespace distributed_test {

using namespace nestlight;
namespace fs = std::filesystem;

using Sources = std::function<std::vector<std::unique_ptr<PointReader>>()>;

BuildOptions options(const fs::path& out) {
  BuildOptions o;
  o.output = out;
  o.progress = ProgressMode::Quiet;
  o.threads = 1;
  o.memoryBytes = 24ull << 20;  // many chunks to share out
  o.dedup = true;
  return o;
}

// Every rank a thread with its own readers of the same inputs; rank 0's report.
BuildReport buildWithRanks(int ranks, const Sources& sources, const fs::path& out,
                           const fs::path& scratch = {}) {
  auto group = threadGroup(ranks);
  const size_t n = static_cast<size_t>(ranks);
  std::vector<BuildReport> reports(n);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r)
    threads.emplace_back([&, r] {
      BuildOptions o = options(out);
      o.comm = group[size_t(r)].get();
      o.scratch = scratch;
      try {
        reports[size_t(r)] = buildOctree(sources(), o);
      } catch (const std::exception& e) {
        // The other ranks may wait for this one in a collective: end the test binary, as
        // `convert --mpi` ends the job.
        std::fprintf(stderr, "rank %d: %s\n", r, e.what());
        group[size_t(r)]->abort(1);
      }
    });
  for (auto& t : threads) t.join();
  return reports[0];
}

// National-grid coordinates: a building, a volume-filling cube in it, one point 20 000 times.
std::vector<std::unique_ptr<PointReader>> hardCases() {
  std::vector<std::unique_ptr<PointReader>> r;
  SyntheticSpec a, b, c;
  a.points = 150000, b.points = 60000, c.points = 20000;
  b.shape = SyntheticShape::Cube, c.shape = SyntheticShape::Duplicates;
  a.seed = 3, b.seed = 4;
  for (SyntheticSpec* s : {&a, &b, &c}) s->origin = {512000, 5412000, 300}, s->size = 40;
  r.push_back(openSynthetic(a));
  r.push_back(openSynthetic(b));
  r.push_back(openSynthetic(c));
  return r;
}

TEST(Distributed, AnyNumberOfRanksBuildsTheSingleProcessOctree) {
  test::TempDir tmp;
  const BuildReport one = buildOctree(hardCases(), options(tmp.path() / "one"));
  ASSERT_GT(one.chunks, 8u) << "too few chunks to share out";
  EXPECT_EQ(one.metadata.accounting.duplicatesMerged, 19999u);
  for (int n : {2, 3, 5}) {  // 5 ranks for 3 inputs: two read nothing
    SCOPED_TRACE(std::to_string(n) + " ranks");
    const fs::path out = tmp.path() / ("ranks" + std::to_string(n));
    const BuildReport r = buildWithRanks(n, hardCases, out, tmp.path() / "scratch");
    test::expectSameNodes(tmp.path() / "one", out);
    EXPECT_TRUE(verifyOctree(out).ok());
    EXPECT_EQ(r.chunks, one.chunks);
    ASSERT_EQ(r.ranks.size(), size_t(n));
    // Every rank indexed a share of the points (contiguous ranges of about equal counts), and
    // the shares add up to every point kept or merged.
    uint64_t indexed = 0;
    for (const auto& k : r.ranks) {
      EXPECT_GT(k["points_indexed"].get<uint64_t>(), 0u) << k.dump();
      indexed += k["points_indexed"].get<uint64_t>();
    }
    EXPECT_EQ(indexed, one.metadata.accounting.kept + one.metadata.accounting.duplicatesMerged);
  }
  EXPECT_TRUE(fs::is_empty(tmp.path() / "scratch"));
}

TEST(Distributed, NoPointAtAll) {
  test::TempDir tmp;
  SyntheticSpec empty;
  empty.points = 0;
  writeSynthetic(empty, tmp.file("empty.las"));  // a LAS file of no record: nothing to split
  const Sources none = [&] {
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openSynthetic(empty));
    r.push_back(openReader(tmp.file("empty.las")));
    return r;
  };
  buildOctree(none(), options(tmp.path() / "one"));
  buildWithRanks(3, none, tmp.path() / "three");
  test::expectSameNodes(tmp.path() / "one", tmp.path() / "three");
}

// A header whose bounds lie by 7.5 m: a point beyond the planned cube makes every rank start over
// with the bounds measured, together.
TEST(Distributed, ALyingHeaderRestartsEveryRank) {
  test::TempDir tmp;
  SyntheticSpec spec;
  spec.points = 60000;
  test::writeLasWithBoundsInset(spec, tmp.file("lying.las"), 7.5);
  spec.seed = 9;
  test::writeLasWithBoundsInset(spec, tmp.file("honest.las"), 0);
  const Sources files = [&] {
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openReader(tmp.file("lying.las")));
    r.push_back(openReader(tmp.file("honest.las")));
    return r;
  };
  const BuildReport one = buildOctree(files(), options(tmp.path() / "one"));
  EXPECT_TRUE(test::anyContains(one.warnings, "measured from the points"));
  const BuildReport two = buildWithRanks(2, files, tmp.path() / "two");
  EXPECT_TRUE(test::anyContains(two.warnings, "measured from the points"));
  test::expectSameNodes(tmp.path() / "one", tmp.path() / "two");
  EXPECT_EQ(OctreeReader(tmp.path() / "two").metadata().sources.at(0).warnings,
            OctreeReader(tmp.path() / "one").metadata().sources.at(0).warnings);
}

// A large input reads in parts: an uncompressed LAS file in ranges of its records, a LAZ file
// in ranges of its chunks. The parts' points, in order, are the whole file's, and a job deals a
// large file's parts to several ranks.
class DistributedParts : public ::testing::TestWithParam<const char*> {};

TEST_P(DistributedParts, ALargeFileIsReadInPartsByEveryRank) {
  test::TempDir tmp;
  const std::string ext = GetParam();
  SyntheticSpec big, small;
  big.points = 200000, small.points = 5000;
  big.seed = 21, small.seed = 22;
  writeSynthetic(big, tmp.file("big" + ext));
  writeSynthetic(small, tmp.file("small.las"));
  {
    auto whole = openReader(tmp.file("big" + ext));
    const uint64_t units = whole->splitUnits();
    ASSERT_GE(units, 3u);
    const auto all = test::readAll(*whole);
    std::vector<double> parts;
    std::vector<uint8_t> attrs;
    for (uint64_t p = 0; p < 3; ++p) {
      auto r = openReader(tmp.file("big" + ext));
      r->restrictTo(units * p / 3, units * (p + 1) / 3);
      r->rewind();
      const auto got = test::readAll(*r);
      parts.insert(parts.end(), got.xyz.begin(), got.xyz.end());
      attrs.insert(attrs.end(), got.attrs.begin(), got.attrs.end());
      EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());
      EXPECT_GT(r->bytesTotal(), 0u);
    }
    EXPECT_EQ(parts, all.xyz);
    EXPECT_EQ(attrs, all.attrs);
  }
  const Sources files = [&] {
    std::vector<std::unique_ptr<PointReader>> r;
    r.push_back(openReader(tmp.file("big" + ext)));
    r.push_back(openReader(tmp.file("small.las")));
    return r;
  };
  buildOctree(files(), options(tmp.path() / "one"));
  const BuildReport three = buildWithRanks(3, files, tmp.path() / "three");
  test::expectSameNodes(tmp.path() / "one", tmp.path() / "three");
  ASSERT_EQ(three.ranks.size(), 3u);
  for (const auto& k : three.ranks) EXPECT_GT(k["input_bytes"].get<uint64_t>(), 0u) << k.dump();
  EXPECT_EQ(OctreeReader(tmp.path() / "three").metadata().sources.at(0).points, 200000u);
}

INSTANTIATE_TEST_SUITE_P(Formats, DistributedParts, ::testing::Values(".las", ".laz"),
                         [](const auto& info) { return std::string(info.param + 1); });

}  // namespace distributed_test
