// The LAZ reader against LAS twins decompressed by an independent LASzip decoder
// (../shared/data/laz: LASzip 2 pointwise chunked files of formats 0-3 with and without extra
// bytes, LAS 1.4 layered chunks of format 6 with an EVLR, a COPC file of format 7), byte for
// byte; streaming equals bulk; parallel equals serial.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <tuple>

#include "nestlight/converters/reader.h"
#include "test_support.h"

using namespace nestlight;
using nestlight::test::sharedData;

namespace {

struct Records {
  size_t recordLength = 0;
  std::vector<uint8_t> bytes;
  SourceHeader header;
  std::vector<std::string> warnings;
  size_t count() const { return recordLength ? bytes.size() / recordLength : 0; }
};

Records records(const std::string& path, const ReadOptions& o = {}) {
  Records r;
  r.recordLength = readLasRecords(
      mapFile(path), o,
      [&](const uint8_t* p, size_t n, size_t length) { r.bytes.insert(r.bytes.end(), p, p + n * length); },
      &r.header, &r.warnings);
  return r;
}

std::string laz(const std::string& name) { return (sharedData() / "laz" / name).string(); }

// The first differing record, for a readable failure.
std::string firstDifference(const Records& a, const Records& b) {
  for (size_t i = 0; i < std::min(a.count(), b.count()); ++i)
    for (size_t k = 0; k < a.recordLength; ++k)
      if (a.bytes[i * a.recordLength + k] != b.bytes[i * b.recordLength + k])
        return "record " + std::to_string(i) + " byte " + std::to_string(k) + ": " +
               std::to_string(a.bytes[i * a.recordLength + k]) + " vs " +
               std::to_string(b.bytes[i * b.recordLength + k]);
  return "counts " + std::to_string(a.count()) + " vs " + std::to_string(b.count());
}

class LazTwin : public ::testing::TestWithParam<std::pair<const char*, const char*>> {};

TEST_P(LazTwin, DecodesToTheRecordsOfTheLasTwinByteForByte) {
  const auto [compressed, plain] = GetParam();
  NL_REQUIRE_SHARED(std::string("laz/") + compressed);
  const std::string lasPath = std::string(plain).find('/') != std::string::npos
                                  ? (sharedData() / plain).string()
                                  : laz(plain);
  const Records z = records(laz(compressed));
  const Records l = records(lasPath);
  EXPECT_EQ(z.header.format, "laz");
  EXPECT_EQ(l.header.format, "las");
  ASSERT_EQ(z.recordLength, l.recordLength);
  ASSERT_EQ(z.count(), *l.header.declaredPoints);
  EXPECT_TRUE(z.bytes == l.bytes) << firstDifference(z, l);
  EXPECT_TRUE(z.warnings.empty()) << z.warnings.front();
  // The decoded fields agree as well (same layout, same extra-bytes names).
  EXPECT_EQ(z.header.layout.stride(), l.header.layout.stride());
  EXPECT_TRUE(z.header.details.contains("laszip"));
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, LazTwin,
    ::testing::Values(std::make_pair("point10.las.laz", "point10.las"),
                      std::make_pair("point-time.las.laz", "point-time.las"),
                      std::make_pair("point-color.las.laz", "point-color.las"),
                      std::make_pair("point-color-time.las.laz", "point-color-time.las"),
                      std::make_pair("extrabytes.laz", "extrabytes.las"),
                      std::make_pair("simple.laz", "simple.las"),
                      std::make_pair("autzen_trim.laz", "scans/autzen_trim.las"),
                      std::make_pair("1_4_w_evlr.laz", "1_4_w_evlr.las")),
    [](const auto& info) {
      std::string n = info.param.first;
      for (char& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return n;
    });

// Streaming in small batches through the PointReader interface gives the points of one bulk
// decode, and one thread gives what all threads give.
TEST(Laz, StreamingEqualsBulkAndSerialEqualsParallel) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  auto zr = openReader(laz("autzen_trim.laz"));
  auto lr = openReader((sharedData() / "scans/autzen_trim.las").string());
  const test::Points zs = test::readAll(*zr, 777);
  const test::Points ls = test::readAll(*lr, 100000);
  ASSERT_EQ(zs.size(), 110000u);
  EXPECT_TRUE(zs.xyz == ls.xyz);
  EXPECT_TRUE(zs.attrs == ls.attrs);
  Records serial;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial = records(laz("autzen_trim.laz"));
  }
  const Records parallel = records(laz("autzen_trim.laz"));
  EXPECT_TRUE(serial.bytes == parallel.bytes);
  // Rewinding starts again from the first point.
  zr->rewind();
  const test::Points again = test::readAll(*zr, 5000);
  EXPECT_TRUE(again.xyz == zs.xyz);
}

}  // namespace
