// A LAS/LAZ file's coordinate reference system survives convert -> export byte for byte: every
// LASF_Projection record (GeoKeyDirectory, GeoDoubleParams, GeoAsciiParams, OGC WKT), as a VLR
// or an EVLR, comes back with the same record id and the same payload.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <map>

#include "nestlight/converters/export.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::TempDir;
namespace fs = std::filesystem;

namespace crs_roundtrip_test {

template <typename T>
T at(const std::string& b, size_t o) {
  T v{};
  if (o + sizeof(T) <= b.size()) std::memcpy(&v, b.data() + o, sizeof(T));
  return v;
}

// record id -> payload of the file's LASF_Projection (E)VLRs, read from its bytes.
std::map<uint16_t, std::string> projectionRecords(const fs::path& file) {
  std::ifstream f(file, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(f)), {});
  std::map<uint16_t, std::string> out;
  size_t p = at<uint16_t>(b, 94);
  for (uint32_t i = 0, n = at<uint32_t>(b, 100); i < n && p + 54 <= b.size(); ++i) {
    const uint16_t len = at<uint16_t>(b, p + 20);
    if (std::string(b.data() + p + 2, strnlen(b.data() + p + 2, 16)) == "LASF_Projection")
      out[at<uint16_t>(b, p + 18)] = b.substr(p + 54, len);
    p += 54 + len;
  }
  if (at<uint8_t>(b, 25) >= 4) {  // LAS 1.4: extended VLRs after the points
    uint64_t q = at<uint64_t>(b, 235);
    for (uint32_t i = 0, n = at<uint32_t>(b, 243); i < n && q + 60 <= b.size(); ++i) {
      const uint64_t len = at<uint64_t>(b, q + 20);
      if (std::string(b.data() + q + 2, strnlen(b.data() + q + 2, 16)) == "LASF_Projection")
        out[at<uint16_t>(b, q + 18)] = b.substr(q + 60, len);
      q += 60 + len;
    }
  }
  return out;
}

}  // namespace crs_roundtrip_test
using namespace crs_roundtrip_test;

TEST(CrsRoundTrip, ProjectionRecordsSurviveConvertAndExportByteForByte) {
  int checked = 0;
  for (const char* rel : {"scans/autzen_trim.las", "scans/autzen_trim_las14_pf7.las"}) {
    const fs::path src = nestlight::test::sharedData() / rel;
    if (!fs::exists(src)) continue;
    SCOPED_TRACE(rel);
    const auto before = projectionRecords(src);
    ASSERT_FALSE(before.empty());
    TempDir tmp;
    nestlight::test::buildOctreeFrom(src, tmp.path() / "o");
    for (const char* ext : {".las", ".laz"}) {
      const fs::path out = tmp.path() / (std::string("back") + ext);
      exportOctree(tmp.path() / "o", out);
      EXPECT_EQ(projectionRecords(out), before) << ext;
      ++checked;
    }
  }
  if (!checked) GTEST_SKIP() << "../shared/data/scans/autzen_trim*.las are absent";
}
