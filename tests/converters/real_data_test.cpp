// Every real scan of ../shared/data/scans converts, verifies, and exports back to the same points
// (to the octree's declared precision) with the same attributes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace {

// Each point as its integer grid position followed by the named attributes' values.
using Row = std::vector<double>;

std::vector<Row> rows(PointReader& r, const Metadata& m, const std::vector<std::string>& names) {
  const PointLayout& l = r.header().layout;
  std::vector<int> idx;
  for (auto& n : names) idx.push_back(l.find(n));
  std::vector<Row> out;
  PointBatch b;
  r.rewind();
  while (r.read(b, 100000)) {
    for (size_t i = 0; i < b.size(); ++i) {
      const double* p = &b.xyz[3 * i];
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
      Row row;
      for (int a = 0; a < 3; ++a)
        row.push_back(double(std::llround((p[a] - m.offset[a]) / m.scale[a])));
      for (int k : idx) {
        if (k < 0) {
          row.push_back(-1e300);  // absent: fails the comparison below
          continue;
        }
        const Attribute& at = l[k];
        for (uint32_t c = 0; c < at.components; ++c)
          row.push_back(loadAsDouble(
              at.type, b.attrs.data() + i * l.stride() + l.offset(k) + c * scalarSize(at.type)));
      }
      out.push_back(std::move(row));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Builds an octree at `output` from `sources`, without progress output.
BuildReport buildQuiet(const std::vector<fs::path>& sources, const fs::path& output) {
  BuildOptions o;
  o.output = output;
  o.progress = ProgressMode::Quiet;
  std::vector<std::unique_ptr<PointReader>> readers;
  for (const fs::path& src : sources) readers.push_back(openReader(src.string()));
  return buildOctree(std::move(readers), o);
}

// Returns the metadata of the build, for checks specific to one scan.
Metadata convertVerifyExport(const std::string& rel, const std::string& exportExt,
                             uint64_t expectedPoints) {
  const fs::path src = nestlight::test::sharedData() / rel;
  TempDir tmp;
  const fs::path octree = tmp.path() / "o";
  BuildReport r = buildQuiet({src}, octree);
  EXPECT_EQ(r.metadata.points, expectedPoints);
  EXPECT_TRUE(r.metadata.accounting.balanced());
  VerifyReport v = verifyOctree(octree);
  for (auto& f : v.failures) ADD_FAILURE() << f;
  EXPECT_TRUE(v.ok());

  const fs::path out = tmp.path() / ("back" + exportExt);
  EXPECT_EQ(exportOctree(octree, out), expectedPoints);
  std::vector<std::string> names;
  for (auto& a : r.metadata.layout.attributes()) names.push_back(a.name);
  auto original = openReader(src.string());
  auto back = openReader(out.string());
  std::vector<Row> a = rows(*original, r.metadata, names), b = rows(*back, r.metadata, names);
  EXPECT_EQ(a.size(), b.size());
  size_t mismatches = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()) && mismatches < 5; ++i)
    if (a[i] != b[i]) {
      ++mismatches;
      ADD_FAILURE() << rel << ": point " << i << " differs after export";
    }
  EXPECT_EQ(mismatches, 0u);
  return r.metadata;
}

}  // namespace

TEST(RealData, LionLas) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  convertVerifyExport("scans/lion_takanawa.las", ".las", 341989);
}
TEST(RealData, LionPlyWithNormals) {
  NL_REQUIRE_SHARED("scans/lion_takanawa_normals.ply");
  convertVerifyExport("scans/lion_takanawa_normals.ply", ".ply", 341989);
}
TEST(RealData, AutzenLas12WithCrs) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  Metadata m = convertVerifyExport("scans/autzen_trim.las", ".las", 110000);
  EXPECT_FALSE(m.crs.is_null());  // the WKT / GeoTIFF VLRs are carried into the metadata
}
TEST(RealData, AutzenLas14Format7) {
  NL_REQUIRE_SHARED("scans/autzen_trim_las14_pf7.las");
  convertVerifyExport("scans/autzen_trim_las14_pf7.las", ".las", 110000);
}
TEST(RealData, KinectPcdSkipsNaN) {
  NL_REQUIRE_SHARED("scans/kinect_indoor.pcd");
  Metadata m = convertVerifyExport("scans/kinect_indoor.pcd", ".ply", 259847);
  EXPECT_EQ(m.accounting.input, 307200u);
  EXPECT_EQ(m.accounting.rejected.at(reject::kNonFinite), 307200u - 259847u);
}
TEST(RealData, AllScansIntoOneOctree) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  TempDir tmp;
  BuildReport r = buildQuiet({nestlight::test::sharedData() / "scans/lion_takanawa.las",
                              nestlight::test::sharedData() / "scans/lion_takanawa_normals.ply"},
                             tmp.path() / "o");
  EXPECT_EQ(r.metadata.points, 2u * 341989);
  EXPECT_TRUE(verifyOctree(tmp.path() / "o").ok());
}
