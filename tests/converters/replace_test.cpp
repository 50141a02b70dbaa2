// Replacing what a user already has: a conversion or export that fails leaves the old octree or
// Potree dataset as it was; a killed conversion's leftovers are noted and cleaned; make-scene
// never overwrites an edited scene or reuses another scene's scan.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/potree_export.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/staged_directory.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

// A synthetic source that fails once `failAfter` points have been read in all (its passes
// together): a damaged file found deep into a conversion, or a disk that filled.
class FailingReader : public PointReader {
 public:
  FailingReader(const SyntheticSpec& s, uint64_t failAfter)
      : inner_(openSynthetic(s)), failAfter_(failAfter) {}
  const SourceHeader& header() const override { return inner_->header(); }
  bool read(PointBatch& b, size_t n) override {
    if (read_ >= failAfter_)
      throw Error("failing.las", "byte 123456", "simulated damage deep in the file");
    const bool more = inner_->read(b, n);
    read_ += b.size();
    return more;
  }
  void rewind() override { inner_->rewind(); }
  uint64_t bytesConsumed() const override { return inner_->bytesConsumed(); }
  uint64_t bytesTotal() const override { return inner_->bytesTotal(); }

 private:
  std::unique_ptr<PointReader> inner_;
  uint64_t failAfter_, read_ = 0;
};

BuildOptions options(const fs::path& out, bool overwrite) {
  BuildOptions o;
  o.output = out;
  o.overwrite = overwrite;
  o.progress = ProgressMode::Quiet;
  o.threads = 2;
  o.maxNodePoints = 2000;
  return o;
}

SyntheticSpec spec(uint64_t points, uint64_t seed) {
  SyntheticSpec s;
  s.points = points;
  s.seed = seed;
  return s;
}

void buildFrom(std::unique_ptr<PointReader> r, const BuildOptions& o) {
  std::vector<std::unique_ptr<PointReader>> v;
  v.push_back(std::move(r));
  buildOctree(std::move(v), o);
}

std::vector<fs::path> siblings(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(Replace, FailedOverwriteKeepsTheOldOctreeItsLayersAndTheUsersFiles) {
  TempDir t;
  const fs::path out = t.path() / "scan.octree";
  buildFrom(openSynthetic(spec(30'000, 1)), options(out, false));
  test::writeColourLayer(out, "hdr", [](const NodeKey&, size_t) {
    return std::array<float, 3>{2.f, 3.f, 4.f};
  });
  test::writeFile((out / "notes.txt").string(), "survey notes");
  const std::string metadata = test::readFile((out / "metadata.json").string());
  const auto before = siblings(out);

  // Without --overwrite: refused, nothing touched.
  Error e = test::errorOf([&] { buildFrom(openSynthetic(spec(10'000, 2)), options(out, false)); });
  EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  // With it, failing after the planning pass (60,000 of 2 x 50,000 points read): the old octree,
  // its HDR layer and the user's file are all as they were, and no staging folder is left.
  e = test::errorOf([&] {
    buildFrom(std::make_unique<FailingReader>(spec(50'000, 3), 60'000), options(out, true));
  });
  EXPECT_NE(std::string(e.what()).find("simulated damage"), std::string::npos) << e.what();
  EXPECT_EQ(test::readFile((out / "metadata.json").string()), metadata);
  EXPECT_EQ(siblings(out), before);
  EXPECT_EQ(siblings(t.path()), std::vector<fs::path>{"scan.octree"});
  VerifyReport v = verifyOctree(out);
  EXPECT_TRUE(v.ok()) << v.failures.front();
  EXPECT_EQ(v.points, 30'000u);
  EXPECT_EQ(v.layers, 1u);

  // A successful overwrite replaces the octree (its old layer goes with it) and keeps notes.txt.
  buildFrom(openSynthetic(spec(10'000, 2)), options(out, true));
  EXPECT_EQ(OctreeReader(out).metadata().points, 10'000u);
  EXPECT_TRUE(OctreeReader(out).metadata().layers.empty());
  EXPECT_EQ(test::readFile((out / "notes.txt").string()), "survey notes");
  EXPECT_TRUE(verifyOctree(out).ok());
  EXPECT_EQ(siblings(t.path()), std::vector<fs::path>{"scan.octree"});
}

TEST(Replace, KilledConversionLeftoversAreNotedAndRemovedByTheNextConversion) {
  TempDir t;
  const fs::path out = t.path() / "scan.octree";
  buildFrom(openSynthetic(spec(5'000, 1)), options(out, false));
  // What a killed run leaves: a staging folder beside the output (this version) and a
  // ".build-PID" folder inside it (earlier versions), of a process id no process has.
  const fs::path beside = t.path() / ".scan.octree.build-999999999",
                 inside = out / ".build-999999998";
  fs::create_directories(beside);
  fs::create_directories(inside);
  test::writeFile((beside / "chunk-r.bin").string(), std::string(1000, 'x'));
  test::writeFile((inside / "chunk-r.bin").string(), std::string(24, 'x'));
  // One of a process that still runs (this one) is nobody's leftover.
  fs::create_directories(t.path() / (".scan.octree.build-" + std::to_string(::getpid())));
  EXPECT_EQ(staleStagingFolders(out).size(), 2u);

  VerifyReport v = verifyOctree(out);
  EXPECT_TRUE(v.ok());
  ASSERT_EQ(v.notes.size(), 2u);
  EXPECT_TRUE(test::anyContains(
      v.notes, beside.string() + ": 1000 bytes left by a conversion that was killed"));
  EXPECT_TRUE(test::anyContains(v.notes, inside.string() + ": 24 bytes"));

  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openSynthetic(spec(5'000, 2)));
  BuildReport rep = buildOctree(std::move(r), options(out, true));
  EXPECT_FALSE(fs::exists(beside));
  EXPECT_FALSE(fs::exists(inside));
  EXPECT_TRUE(test::anyContains(rep.warnings, "left by a conversion that was killed"));
  EXPECT_TRUE(verifyOctree(out).notes.empty());
}

TEST(Replace, FailedPotreeExportKeepsTheOldDataset) {
  TempDir t;
  const fs::path good = t.path() / "good.octree", bad = t.path() / "bad.octree",
                 web = t.path() / "web";
  buildFrom(openSynthetic(spec(20'000, 1)), options(good, false));
  buildFrom(openSynthetic(spec(20'000, 2)), options(bad, false));
  PotreeExportOptions po;
  po.progress = ProgressMode::Quiet;
  exportPotree(good, web, po);
  test::writeFile((web / "index.html").string(), "<html>viewer</html>");
  const std::string metadata = test::readFile((web / "metadata.json").string());
  const std::string payload = test::readFile((web / "octree.bin").string());
  // Damage the second octree's payload (past its root node): its export fails part way.
  {
    std::string bytes = test::readFile((bad / "octree.bin").string());
    for (size_t i = bytes.size() / 2; i < bytes.size(); i += 97) bytes[i] = char(bytes[i] ^ 0x5a);
    test::writeFile((bad / "octree.bin").string(), bytes);
  }
  po.overwrite = true;
  EXPECT_THROW(exportPotree(bad, web, po), Error);
  EXPECT_EQ(test::readFile((web / "metadata.json").string()), metadata);
  EXPECT_EQ(test::readFile((web / "octree.bin").string()), payload);
  EXPECT_EQ(test::readFile((web / "index.html").string()), "<html>viewer</html>");
  std::vector<fs::path> expected{"bad.octree", "good.octree", "web"};
  EXPECT_EQ(siblings(t.path()), expected);
}

TEST(Replace, MakeSceneNeverOverwritesAnEditedSceneOrReusesAnotherScenesScan) {
  TempDir t;
  const fs::path dir = t.path() / "room";
  TestSceneOptions o;
  o.points = 20'000;
  o.quiet = true;
  const fs::path file = makeTestScene(TestSceneKind::Cornell, dir, o);
  const auto octreeTime = fs::last_write_time(dir / "scan.octree" / "metadata.json");
  // The same scene again: nothing to do, the scan is reused.
  makeTestScene(TestSceneKind::Cornell, dir, o);
  EXPECT_EQ(fs::last_write_time(dir / "scan.octree" / "metadata.json"), octreeTime);
  // Another scene over it: refused, the scene file untouched.
  const std::string cornell = test::readFile(file.string());
  Error e = test::errorOf([&] { makeTestScene(TestSceneKind::Nave, dir, o); });
  EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  EXPECT_EQ(test::readFile(file.string()), cornell);
  // An edited scene file is never overwritten without --overwrite.
  test::writeFile(file.string(), cornell + " ");
  e = test::errorOf([&] { makeTestScene(TestSceneKind::Cornell, dir, o); });
  EXPECT_NE(std::string(e.what()).find("differs"), std::string::npos) << e.what();
  // A scan made from other points is not reused even where the scene file was removed.
  fs::remove(file);
  TestSceneOptions more = o;
  more.points = 30'000;
  e = test::errorOf([&] { makeTestScene(TestSceneKind::Cornell, dir, more); });
  EXPECT_NE(std::string(e.what()).find("not made for this scene"), std::string::npos) << e.what();
  // With --overwrite: a nave, with the nave's scan.
  more.overwrite = true;
  makeTestScene(TestSceneKind::Nave, dir, more);
  EXPECT_EQ(OctreeReader(dir / "scan.octree").metadata().points, 30'000u);
  EXPECT_NE(test::readFile(file.string()).find("statue"), std::string::npos);
}
