// `mpirun -n N nestlight convert --mpi` on this machine's loopback (Open MPI, --oversubscribe):
// 1 to 4 ranks build octrees holding the same points in the same nodes as one process, with the
// same accounting, on generated scans (duplicates merged, a volume-filling cube, national-grid
// coordinates) and on the shared LAZ files; a rank that dies and a rank whose scratch disk fills
// end the job with no octree committed, and a rerun starts clean. Skipped where mpirun is missing
// or the program was built without MPI.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

namespace convert_mpi_test {

namespace fs = std::filesystem;
using nestlight::test::runCli;
using nestlight::test::TempDir;

// Runs `cmd` through the shell, stdout and stderr into *out.
int shell(const std::string& cmd, const TempDir& tmp, std::string* out) {
  const int rc = std::system((cmd + " > " + tmp.file("log.txt") + " 2>&1").c_str());
  *out = nestlight::test::readFile(tmp.file("log.txt"));
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128;
}

// mpirun with N ranks on this machine; root may run it (CI runs as root) and ranks may outnumber
// the cores. Each rank's shell may prepend set-up (`perRank`, with $OMPI_COMM_WORLD_RANK).
std::string mpirun(int ranks, const std::string& args, const std::string& perRank = "") {
  const std::string program = nestlight::test::nestlightBinary() + " " + args;
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
         "OMPI_MCA_rmaps_base_oversubscribe=1 "
         "mpirun --oversubscribe -n " +
         std::to_string(ranks) +
         (perRank.empty() ? " " + program : " bash -c '" + perRank + "; exec " + program + "'");
}

class ConvertMpi : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v mpirun > /dev/null 2>&1") != 0)
      GTEST_SKIP() << "mpirun is not installed (scripts/setup.sh installs Open MPI)";
    // Open MPI's own allocations at exit are not the program's leaks.
    ::setenv("ASAN_OPTIONS", "detect_leaks=0", 1);
    std::string out;
    nestlight::test::writeFile(tmp.file("probe.xyz"), "0 0 0\n1 1 1\n");
    if (runCli("convert " + tmp.file("probe.xyz") + " -o " + tmp.file("probe.octree") +
                   " --progress quiet --mpi",
               &out) != 0 &&
        out.find("without MPI") != std::string::npos)
      GTEST_SKIP() << "this nestlight was built without MPI";
  }
  TempDir tmp;
  std::string out;
};

TEST_F(ConvertMpi, OneToFourRanksBuildTheSingleProcessOctree) {
  // National-grid coordinates: a building, a volume-filling cube inside it and one point repeated
  // 30 000 times, merged (--dedup); a small budget makes many chunks to share out.
  const std::string origin = " --origin 512000,5412000,300 --size 40";
  ASSERT_EQ(runCli("generate -o " + tmp.file("a.las") + " -n 250k --seed 3" + origin, &out), 0)
      << out;
  ASSERT_EQ(
      runCli("generate -o " + tmp.file("b.laz") + " --shape cube -n 120k --seed 4" + origin, &out),
      0)
      << out;
  ASSERT_EQ(
      runCli("generate -o " + tmp.file("c.las") + " --shape duplicates -n 30k" + origin, &out), 0)
      << out;
  const std::string inputs = tmp.file("a.las") + " " + tmp.file("b.laz") + " " + tmp.file("c.las");
  const std::string opts = " --dedup --memory 24M --threads 1 --progress quiet";
  ASSERT_EQ(runCli("convert " + inputs + " -o " + tmp.file("one.octree") + opts, &out), 0) << out;
  const nestlight::OctreeReader one(tmp.file("one.octree"));
  EXPECT_GT(one.metadata().build.value("chunks", 0), 8) << "too few chunks to share out";
  EXPECT_GT(one.metadata().accounting.duplicatesMerged, 29000u);
  for (int n = 1; n <= 4; ++n) {
    const std::string dir = tmp.file("mpi" + std::to_string(n) + ".octree");
    ASSERT_EQ(shell(mpirun(n, "convert " + inputs + " -o " + dir + opts + " --mpi --scratch " +
                                  tmp.file("scratch")),
                    tmp, &out),
              0)
        << out;
    SCOPED_TRACE(std::to_string(n) + " ranks");
    nestlight::test::expectSameNodes(tmp.file("one.octree"), dir);
    EXPECT_EQ(nestlight::OctreeReader(dir).metadata().build["command_line"]["ranks"], n);
    if (n > 1) {
      EXPECT_NE(out.find("rank " + std::to_string(n - 1)), std::string::npos) << out;
    }
    ASSERT_EQ(runCli("verify " + dir, &out), 0) << out;
  }
  // Nothing is left in the scratch folder.
  EXPECT_TRUE(fs::is_empty(tmp.file("scratch")));
}

TEST_F(ConvertMpi, SharedLazFilesBuildTheSingleProcessOctree) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const fs::path laz = nestlight::test::sharedData() / "laz";
  // Autzen (LAZ written by other tools; 8 chunks at this budget) over 3 ranks, and four small
  // LAZ files of different point formats together over 2 (the inputs dealt out).
  const std::vector<std::pair<std::string, int>> jobs = {
      {(laz / "autzen_trim.laz").string(), 3},
      {(laz / "point-color.las.laz").string() + " " + (laz / "point-time.las.laz").string() + " " +
           (laz / "point10.las.laz").string() + " " + (laz / "simple.laz").string(),
       2}};
  const std::string opts = " --memory 16M --progress quiet --overwrite";
  for (const auto& [inputs, ranks] : jobs) {
    SCOPED_TRACE(inputs);
    ASSERT_EQ(runCli("convert " + inputs + " -o " + tmp.file("one.octree") + opts, &out), 0) << out;
    ASSERT_EQ(shell(mpirun(ranks,
                           "convert " + inputs + " -o " + tmp.file("mpi.octree") + opts + " --mpi"),
                    tmp, &out),
              0)
        << out;
    nestlight::test::expectSameNodes(tmp.file("one.octree"), tmp.file("mpi.octree"));
  }
}

TEST_F(ConvertMpi, ARankThatDiesOrFillsItsDiskCommitsNothingAndARerunIsClean) {
  ASSERT_EQ(runCli("generate -o " + tmp.file("a.las") + " -n 200k --seed 5", &out), 0) << out;
  const std::string args = "convert " + tmp.file("a.las") + " -o " + tmp.file("out.octree") +
                           " --memory 24M --progress quiet --mpi --scratch " + tmp.file("s");
  // Rank 1 may write 64 KiB per file: its chunk files outgrow that early in the distribution.
  // Without the signal ignored the kernel kills it (SIGXFSZ): a rank that dies.
  const std::string limit = "if [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then ulimit -f 64; fi";
  EXPECT_NE(shell(mpirun(3, args, limit), tmp, &out), 0) << out;
  EXPECT_FALSE(fs::exists(tmp.file("out.octree/metadata.json"))) << out;
  // With the signal ignored the write fails: the rank's error names it, and the job ends.
  const std::string full =
      "if [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then trap \"\" XFSZ; ulimit -f 64; fi";
  EXPECT_NE(shell(mpirun(3, args, full), tmp, &out), 0) << out;
  EXPECT_NE(out.find("rank 1 of 3"), std::string::npos) << out;
  EXPECT_NE(out.find("disk full"), std::string::npos) << out;
  EXPECT_NE(out.find("no octree was committed"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(tmp.file("out.octree/metadata.json"))) << out;
  // A rerun removes what the failed ones left and builds the octree one process builds.
  ASSERT_EQ(shell(mpirun(3, args), tmp, &out), 0) << out;
  ASSERT_EQ(runCli("convert " + tmp.file("a.las") + " -o " + tmp.file("one.octree") +
                       " --memory 24M --progress quiet",
                   &out),
            0)
      << out;
  nestlight::test::expectSameNodes(tmp.file("one.octree"), tmp.file("out.octree"));
  EXPECT_TRUE(fs::is_empty(tmp.file("s")));
  for (const auto& e : fs::directory_iterator(tmp.file("out.octree")))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// `bench convert --mpi`: one process and each rank count, with the bytes each job sent and its
// ranks' reports.
TEST_F(ConvertMpi, BenchReportsEachRankCount) {
  ASSERT_EQ(runCli("bench convert --sizes 80k --runs 1 --mpi 1,2 --memory 64M --dir " +
                       tmp.file("b") + " --json " + tmp.file("b.json"),
                   &out),
            0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(nestlight::test::readFile(tmp.file("b.json")));
  ASSERT_EQ(j["runs"].size(), 3u) << j.dump(1);
  EXPECT_EQ(j["runs"][0]["ranks"], 0);  // one process, without MPI
  EXPECT_EQ(j["runs"][2]["ranks"], 2);
  EXPECT_EQ(j["runs"][2]["report"]["ranks"].size(), 2u);
  // Two ranks move about half the points as 30-byte records (the tiles are LAS format 2).
  const double sent = j["runs"][2]["bytes_sent_per_point"].get<double>();
  EXPECT_GT(sent, 5.0);
  EXPECT_LT(sent, 40.0);
  EXPECT_EQ(j["runs"][1]["bytes_sent_per_point"].get<double>(), 0.0);
}

}  // namespace convert_mpi_test
