// The LAZ reader against LAS twins decompressed by an independent LASzip decoder
// (../shared/data/laz: LASzip 2 pointwise chunked files of formats 0-3 with and without extra
// bytes, LAS 1.4 layered chunks of format 6 with an EVLR, a COPC file of format 7), byte for
// byte; streaming equals bulk; parallel equals serial.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <tuple>

#include "nestlight/converters/reader.h"
#include "nestlight/converters/verify.h"
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
      [&](const uint8_t* p, size_t n, size_t length) {
        r.bytes.insert(r.bytes.end(), p, p + n * length);
      },
      &r.header, &r.warnings);
  return r;
}

std::string laz(const std::string& name) {
  return (sharedData() / "laz" / name).string();
}

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

// COPC: the points of simple.las, in another order (the COPC hierarchy's) and another record
// format (7 instead of 3): the same multiset of positions and shared fields.
TEST(Laz, CopcHoldsThePointsOfItsLasTwin) {
  NL_REQUIRE_SHARED("laz/simple.copc.laz");
  auto c = openReader(laz("simple.copc.laz"));
  auto l = openReader(laz("simple.las"));
  const test::Points cp = test::readAll(*c, 100);
  const test::Points lp = test::readAll(*l, 100);
  ASSERT_EQ(cp.size(), 1065u);
  ASSERT_EQ(lp.size(), 1065u);
  using Row = std::tuple<int64_t, int64_t, int64_t, uint16_t, uint8_t, uint8_t, uint8_t, double,
                         uint16_t, uint16_t, uint16_t, uint16_t>;
  // Both files quantise to 0.01 but from different offsets: compare world positions on that grid.
  const Vec3d sc = *l->header().scale;
  auto rows = [&sc](const test::Points& p, const PointReader& r) {
    std::vector<Row> out;
    for (size_t i = 0; i < p.size(); ++i) {
      auto q = [&](int a) { return int64_t(std::llround(p.xyz[3 * i + a] / sc[a])); };
      out.emplace_back(
          q(0), q(1), q(2), test::attrAt<uint16_t>(p, r, i, "intensity"),
          test::attrAt<uint8_t>(p, r, i, "return_number"),
          test::attrAt<uint8_t>(p, r, i, "number_of_returns"),
          test::attrAt<uint8_t>(p, r, i, "classification"),
          test::attrAt<double>(p, r, i, "gps_time"), test::attrAt<uint16_t>(p, r, i, "rgb", 0),
          test::attrAt<uint16_t>(p, r, i, "rgb", 1), test::attrAt<uint16_t>(p, r, i, "rgb", 2),
          test::attrAt<uint16_t>(p, r, i, "point_source_id"));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  EXPECT_EQ(*c->header().scale, sc);
  EXPECT_TRUE(rows(cp, *c) == rows(lp, *l));
  EXPECT_EQ(c->header().details["laszip"]["compressor"], "layered chunked");
  EXPECT_EQ(c->header().details["laszip"]["chunk_size"], "variable");
}

// COPC lists its chunks in its hierarchy as well: they agree with the chunk table, and when the
// table is lost the hierarchy finds every chunk (variable-size chunks cannot be found otherwise).
TEST(Laz, CopcHierarchyAgreesWithTheTableAndStandsInForIt) {
  NL_REQUIRE_SHARED("laz/simple.copc.laz");
  std::string f = test::readFile(laz("simple.copc.laz"));
  {
    auto r = openLas(memorySource("a.copc.laz", std::vector<uint8_t>(f.begin(), f.end())));
    EXPECT_EQ(r->header().details["copc"]["chunks"], 65);
    EXPECT_EQ(r->header().details["laszip"]["chunks_from"], "chunk table");
    EXPECT_TRUE(r->warnings().empty());
  }
  uint32_t pointStart;
  std::memcpy(&pointStart, f.data() + 96, 4);
  const int64_t past = int64_t(f.size()) + 1000;
  std::memcpy(f.data() + pointStart, &past, 8);  // the chunk table offset now points nowhere
  auto r = openLas(memorySource("b.copc.laz", std::vector<uint8_t>(f.begin(), f.end())));
  EXPECT_EQ(r->header().details["laszip"]["chunks_from"], "COPC hierarchy");
  EXPECT_TRUE(test::anyContains(r->warnings(), "read from the COPC hierarchy"));
  // The same points, in the same order, as through the chunk table.
  auto tabled = openReader(laz("simple.copc.laz"));
  const test::Points p = test::readAll(*r, 100), q = test::readAll(*tabled, 100);
  EXPECT_EQ(p.size(), 1065u);
  EXPECT_TRUE(p.xyz == q.xyz);
  EXPECT_TRUE(p.attrs == q.attrs);
  // Without hierarchy and table, a variable-size chunked file cannot be read: a clear error.
  std::string g = f;
  const size_t copc = g.find("copc");
  ASSERT_NE(copc, std::string::npos);
  g[copc] = 'x';  // no longer a COPC info VLR
  const Error e = test::errorOf(
      [&] { openLas(memorySource("c.laz", std::vector<uint8_t>(g.begin(), g.end()))); });
  EXPECT_NE(e.reason().find("variable-size chunks cannot be read without it"), std::string::npos)
      << e.what();
}

// ---- the coder --------------------------------------------------------------------------------

#include "laz/arithmetic.h"

namespace {

// Decoding inverts encoding on every path of the models: bits, symbols of small and table-driven
// models across many updates, raw bits of every width, and integers of every magnitude through
// the corrector models (including k above bitsHigh, where low bits go raw).
TEST(LazCoder, DecodingInvertsEncodingOnEveryModelPath) {
  std::vector<uint8_t> stream;
  uint64_t state = 12345;
  auto next = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<uint32_t>(state >> 33);
  };
  struct Op {
    int kind;
    uint32_t a, b;
  };
  std::vector<Op> ops;
  for (int i = 0; i < 20000; ++i) {
    const int kind = int(next() % 5);
    uint32_t a = next(), b = 0;
    switch (kind) {
      case 0:
        a &= 1;
        break;  // bit, skewed below
      case 1:
        a = (next() & 7) ? a % 3 : a % 2048;
        break;  // symbol of 2048
      case 2:
        b = 1 + next() % 32;
        a = b == 32 ? a : a & ((1u << b) - 1);
        break;  // raw bits
      case 3:
        a = uint32_t(int32_t(a) >> (next() % 31));
        b = next() % 4;
        break;  // integer
      case 4:
        a %= 256;
        break;  // symbol of 256
    }
    if (kind == 0 && (next() % 10)) a = 0;
    ops.push_back({kind, a, b});
  }
  {
    laz::ArithmeticEncoder enc(stream);
    laz::BitModel bit;
    laz::SymbolModel big(2048), small(256);
    laz::IntegerDecoder ic(32, 4);
    int32_t pred = 0;
    for (const Op& op : ops) {
      switch (op.kind) {
        case 0:
          enc.encodeBit(bit, op.a);
          break;
        case 1:
          enc.encodeSymbol(big, op.a);
          break;
        case 2:
          enc.writeBits(op.b, op.a);
          break;
        case 3:
          ic.compress(enc, pred, int32_t(op.a), op.b);
          pred = int32_t(op.a) / 2;
          break;
        case 4:
          enc.encodeSymbol(small, op.a);
          break;
      }
    }
    enc.done();
  }
  laz::ArithmeticDecoder dec;
  dec.init(stream.data(), stream.data() + stream.size());
  laz::BitModel bit;
  laz::SymbolModel big(2048), small(256);
  laz::IntegerDecoder ic(32, 4);
  int32_t pred = 0;
  size_t wrong = 0;
  for (const Op& op : ops) {
    uint32_t got = 0;
    switch (op.kind) {
      case 0:
        got = dec.decodeBit(bit);
        break;
      case 1:
        got = dec.decodeSymbol(big);
        break;
      case 2:
        got = dec.readBits(op.b);
        break;
      case 3:
        got = uint32_t(ic.decompress(dec, pred, op.b));
        pred = int32_t(got) / 2;
        break;
      case 4:
        got = dec.decodeSymbol(small);
        break;
    }
    wrong += got != op.a;
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(dec.overrun(), 0u) << "the encoder's padding keeps the decoder inside the stream";
  EXPECT_LE(stream.size() - dec.consumed(), 4u);
}

// Garbage decodes to garbage, in bounds and in finite time, and running dry is reported.
TEST(LazCoder, GarbageStaysInBoundsAndRunningDryIsCounted) {
  std::vector<uint8_t> junk(64);
  for (size_t i = 0; i < junk.size(); ++i) junk[i] = uint8_t(i * 131 + 7);
  laz::ArithmeticDecoder dec;
  dec.init(junk.data(), junk.data() + junk.size());
  laz::SymbolModel m(300);
  laz::IntegerDecoder ic(32, 2);
  for (int i = 0; i < 2000; ++i) {
    EXPECT_LT(dec.decodeSymbol(m), 300u);
    (void)ic.decompress(dec, i, i & 1);
  }
  EXPECT_GT(dec.overrun(), 0u);
  EXPECT_EQ(dec.consumed(), junk.size());
}

// ---- damaged files ------------------------------------------------------------------------------

template <typename T>
T load(const std::string& s, size_t at) {
  T v;
  std::memcpy(&v, s.data() + at, sizeof v);
  return v;
}
template <typename T>
void store(std::string& s, size_t at, T v) {
  std::memcpy(s.data() + at, &v, sizeof v);
}

// A LASzip 2 file (fixed chunk size) and its chunk table, decoded here from the format's rules.
struct LazLayout {
  uint64_t pointStart = 0, table = 0;
  std::vector<uint32_t> bytes;  // per chunk
  uint64_t chunkStart(size_t i) const {
    uint64_t at = pointStart + 8;
    for (size_t k = 0; k < i; ++k) at += bytes[k];
    return at;
  }
};

LazLayout layoutOf(const std::string& f) {
  LazLayout l;
  l.pointStart = load<uint32_t>(f, 96);
  l.table = uint64_t(load<int64_t>(f, l.pointStart));
  const uint32_t n = load<uint32_t>(f, l.table + 4);
  laz::ArithmeticDecoder dec;
  const auto* d = reinterpret_cast<const uint8_t*>(f.data());
  dec.init(d + l.table + 8, d + f.size());
  laz::IntegerDecoder ic(32, 2);
  for (uint32_t i = 0; i < n; ++i)
    l.bytes.push_back(uint32_t(ic.decompress(dec, i ? int32_t(l.bytes.back()) : 0, 1)));
  return l;
}

// The file with its chunk table replaced by one that lists `bytes`.
std::string withTable(std::string f, const LazLayout& l, const std::vector<uint32_t>& bytes) {
  f.resize(l.table);
  std::vector<uint8_t> t(8);
  const uint32_t n = uint32_t(bytes.size());
  std::memcpy(t.data() + 4, &n, 4);
  {
    laz::ArithmeticEncoder enc(t);
    laz::IntegerDecoder ic(32, 2);
    for (uint32_t i = 0; i < n; ++i)
      ic.compress(enc, i ? int32_t(bytes[i - 1]) : 0, int32_t(bytes[i]), 1);
    enc.done();
  }
  f.append(reinterpret_cast<const char*>(t.data()), t.size());
  return f;
}

std::string autzenLaz() {
  return test::readFile(laz("autzen_trim.laz"));
}

Error errorReading(const std::string& bytes, bool lenient = false) {
  return test::errorOf([&] {
    ReadOptions o;
    o.lenient = lenient;
    auto r =
        openLas(memorySource("damaged.laz", std::vector<uint8_t>(bytes.begin(), bytes.end())), o);
    test::readAll(*r, 100000);
  });
}

struct LenientRead {
  uint64_t points = 0, unreadable = 0;
  std::vector<std::string> warnings;
};
LenientRead readLeniently(const std::string& bytes) {
  ReadOptions o;
  o.lenient = true;
  auto r =
      openLas(memorySource("damaged.laz", std::vector<uint8_t>(bytes.begin(), bytes.end())), o);
  LenientRead out;
  out.points = test::readAll(*r, 100000).size();
  out.unreadable = r->pointsUnreadable();
  out.warnings = r->warnings();
  return out;
}

TEST(LazDamage, TheTestFileHasThreeChunksAndReencodingItsTableChangesNothing) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const std::string f = autzenLaz();
  const LazLayout l = layoutOf(f);
  ASSERT_EQ(l.bytes.size(), 3u);
  EXPECT_EQ(l.chunkStart(3), l.table);
  // Our encoder writes the table the reference wrote, bit for bit.
  EXPECT_EQ(withTable(f, l, l.bytes), f);
}

TEST(LazDamage, TruncatedFileNamesTheChunkAndOffset) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const std::string f = autzenLaz();
  const LazLayout l = layoutOf(f);
  const uint64_t cut = l.chunkStart(1) + 1000;
  const std::string t = f.substr(0, cut);
  const Error e = errorReading(t);
  EXPECT_EQ(e.file(), "damaged.laz");
  EXPECT_NE(e.reason().find("chunk 2 (points 50001-100000)"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("truncated"), std::string::npos) << e.what();
  EXPECT_EQ(e.position(), Error::atByte(cut)) << e.what();
  // Lenient: the intact first chunk is kept, the rest counted, nothing twice.
  const LenientRead r = readLeniently(t);
  EXPECT_EQ(r.points, 50000u);
  EXPECT_EQ(r.unreadable, 60000u);
  EXPECT_TRUE(test::anyContains(r.warnings, "chunk 2")) << r.warnings.size();
}

TEST(LazDamage, ChunkTablePointingPastTheEndIsAnError) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const std::string f = autzenLaz();
  const LazLayout l = layoutOf(f);
  std::vector<uint32_t> b = l.bytes;
  b[1] += 1u << 20;  // chunk 2 claims a megabyte more than the file holds
  const std::string bad = withTable(f, l, b);
  const Error e = errorReading(bad);
  EXPECT_NE(e.reason().find("chunk 2 of 3"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("runs past the start of the chunk table"), std::string::npos)
      << e.what();
  EXPECT_EQ(e.position(), Error::atByte(l.chunkStart(1)));
  // Read leniently, the table is taken for damaged and the chunks are found one after the other.
  const LenientRead r = readLeniently(bad);
  EXPECT_EQ(r.points, 110000u);
  EXPECT_EQ(r.unreadable, 0u);
  EXPECT_TRUE(test::anyContains(r.warnings, "the chunk table is damaged"));
  // And the offset of the table itself pointing past the end: chunks are found one by one.
  std::string far = f;
  store<int64_t>(far, l.pointStart, int64_t(f.size() + 100));
  const LenientRead g = readLeniently(far);
  EXPECT_EQ(g.points, 110000u);
  EXPECT_TRUE(test::anyContains(g.warnings, "points past the end of the file"));
}

TEST(LazDamage, ZeroLengthChunkNamesTheChunk) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const std::string f = autzenLaz();
  const LazLayout l = layoutOf(f);
  const std::string bad = withTable(f, l, {l.bytes[0], 0, l.bytes[1] + l.bytes[2]});
  const Error e = errorReading(bad);
  EXPECT_NE(e.reason().find("chunk 2 of 3 (points 50001-100000)"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("0 bytes"), std::string::npos) << e.what();
  EXPECT_EQ(e.position(), Error::atByte(l.chunkStart(1)));
  // Lenient keeps chunk 1; chunk 3 now starts at chunk 2's data and holds 10,000 points of it,
  // which decode (to chunk 2's first points): the table is the authority on where chunks are.
  const LenientRead r = readLeniently(bad);
  EXPECT_EQ(r.unreadable, 50000u);
  EXPECT_EQ(r.points, 60000u);
}

TEST(LazDamage, PointCountLargerThanTheDataIsAnError) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  std::string f = autzenLaz();
  store<uint32_t>(f, 107, 110000 + 50001);  // one more chunk's worth than the table lists
  const Error e = errorReading(f);
  EXPECT_NE(
      e.reason().find("header declares 160001 points but the 3 LAZ chunks hold at most 150000"),
      std::string::npos)
      << e.what();
  // One point more than the last chunk holds: that chunk's stream runs dry.
  std::string g = autzenLaz();
  store<uint32_t>(g, 107, 110001);
  const Error e2 = errorReading(g);
  EXPECT_NE(e2.reason().find("chunk 3 of 3 (points 100001-110001)"), std::string::npos)
      << e2.what();
}

TEST(LazDamage, UnknownCompressorOrItemNamesTheRecord) {
  NL_REQUIRE_SHARED("laz/point10.las.laz");
  const std::string f = test::readFile(laz("point10.las.laz"));
  // Find the LASzip VLR.
  const uint16_t headerSize = load<uint16_t>(f, 94);
  size_t p = headerSize, vlr = 0;
  for (uint32_t i = 0; i < load<uint32_t>(f, 100); ++i) {
    if (load<uint16_t>(f, p + 18) == 22204) vlr = p;
    p += 54 + load<uint16_t>(f, p + 20);
  }
  ASSERT_NE(vlr, 0u);
  std::string c = f;
  store<uint16_t>(c, vlr + 54, 9);
  const Error e = errorReading(c);
  EXPECT_NE(e.reason().find("unknown compressor 9"), std::string::npos) << e.what();
  EXPECT_EQ(e.position(), Error::atByte(vlr + 54));
  std::string it = f;
  store<uint16_t>(it, vlr + 54 + 34, 99);
  EXPECT_NE(errorReading(it).reason().find("item 1 has the unknown type 99"), std::string::npos);
  std::string v = f;
  store<uint16_t>(v, vlr + 54 + 34 + 4, 7);
  EXPECT_NE(errorReading(v).reason().find("version 7 is not supported"), std::string::npos);
  std::string none = f;
  std::memcpy(none.data() + vlr + 2, "not laszip", 11);
  EXPECT_NE(errorReading(none).reason().find("there is no LASzip record"), std::string::npos);
}

}  // namespace

// ---- LAZ output -------------------------------------------------------------------------------

#include "nestlight/converters/point_writer.h"

namespace {

// Every LAS twin written as LAZ reads back to the same records, and compresses about as well as
// LASzip itself did (the encoder makes the reference encoder's choices).
TEST(LazWriter, RoundTripsTheTwinsAndCompressesLikeLaszip) {
  const std::pair<const char*, const char*> twins[] = {
      {"point10.las", "point10.las.laz"},
      {"point-time.las", "point-time.las.laz"},
      {"point-color.las", "point-color.las.laz"},
      {"point-color-time.las", "point-color-time.las.laz"},
      {"extrabytes.las", "extrabytes.laz"}};
  NL_REQUIRE_SHARED("laz/point10.las");
  test::TempDir t;
  for (auto [plain, reference] : twins) {
    SCOPED_TRACE(plain);
    auto r = openReader(laz(plain));
    const std::string out = t.file(std::string(plain) + ".laz");
    {
      auto w = createWriter(out, r->header());
      PointBatch b;
      while (r->read(b, 300)) w->write(b);
      w->close();
    }
    const Records back = records(out), orig = records(laz(plain));
    ASSERT_EQ(back.recordLength, orig.recordLength);
    EXPECT_TRUE(back.bytes == orig.bytes) << firstDifference(back, orig);
    EXPECT_EQ(back.header.details["laszip"]["compressor"], "pointwise chunked");
    // The compressed point data (from the point offset to the end: chunks and chunk table) is
    // within 1% of what LASzip wrote; the headers differ by the VLRs each writer adds.
    auto pointBytes = [](const std::string& path) {
      const std::string f = test::readFile(path);
      return double(f.size() - load<uint32_t>(f, 96));
    };
    const double ours = pointBytes(out), theirs = pointBytes(laz(reference));
    EXPECT_NEAR(ours / theirs, 1.0, 0.01) << ours << " vs " << theirs;
  }
}

TEST(LazWriter, ManyChunksRoundTripThroughTheConverterPath) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  test::TempDir t;
  auto r = openReader((sharedData() / "scans/autzen_trim.las").string());
  const std::string out = t.file("a.laz");
  {
    auto w = createWriter(out, r->header());
    PointBatch b;
    while (r->read(b, 4096)) w->write(b);
    w->close();
  }
  const Records back = records(out);
  EXPECT_EQ(back.header.details["laszip"]["chunks"], 3);
  EXPECT_TRUE(back.bytes == records(laz("autzen_trim.laz")).bytes);
  EXPECT_FALSE(std::filesystem::exists(out + ".tmp"));
  EXPECT_FALSE(std::filesystem::exists(out + ".laztmp"));
}

}  // namespace

#include "nestlight/octree/octree_reader.h"

namespace {

// A table-less file is read chunk by chunk; a second pass (the converter makes two) finds the
// chunks again where the first one found them.
TEST(LazDamage, FileWithoutAChunkTableConvertsInTwoPasses) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  std::string f = autzenLaz();
  const LazLayout l = layoutOf(f);
  store<int64_t>(f, l.pointStart, int64_t(l.pointStart));  // "the compressor was interrupted"
  test::TempDir t;
  test::writeFile(t.file("n.laz"), f);
  std::string out;
  ASSERT_EQ(
      test::runCli("convert " + t.file("n.laz") + " -o " + t.file("o") + " --progress quiet", &out),
      0)
      << out;
  OctreeReader r(t.path() / "o");
  EXPECT_EQ(r.metadata().accounting.input, 110000u);
  EXPECT_EQ(r.metadata().sources.at(0).details["laszip"]["chunks_from"], "sequential");
}

// Deferred batches decode on any thread, concurrently, to what one thread reads.
TEST(Laz, DeferredBatchesFinishConcurrently) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  auto serial = openReader(laz("autzen_trim.laz"));
  const test::Points want = test::readAll(*serial, 100000);
  auto r = openReader(laz("autzen_trim.laz"));
  std::vector<PointBatch> batches(8);
  size_t n = 0;
  while (n < batches.size() && r->readDeferred(batches[n], 20000, 1)) ++n;
  ASSERT_GE(n, 3u);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < n; ++i) threads.emplace_back([&, i] { batches[i].finish(); });
  for (auto& th : threads) th.join();
  test::Points got;
  for (size_t i = 0; i < n; ++i) {
    got.xyz.insert(got.xyz.end(), batches[i].xyz.begin(), batches[i].xyz.end());
    got.attrs.insert(got.attrs.end(), batches[i].attrs.begin(), batches[i].attrs.end());
  }
  ASSERT_EQ(got.size(), want.size());
  EXPECT_TRUE(got.xyz == want.xyz);
  EXPECT_TRUE(got.attrs == want.attrs);
}

// Variable-size chunks (COPC): a chunk past the table, read leniently, loses its points and the
// following ones to the accounting, and a header that declares fewer points than the chunks hold
// is said to and every point they hold is read; either way every point is delivered or counted,
// once.
TEST(LazDamage, VariableChunksAccountForEveryDeclaredPoint) {
  NL_REQUIRE_SHARED("laz/simple.copc.laz");
  const std::string f = test::readFile(laz("simple.copc.laz"));
  const uint64_t pointStart = load<uint32_t>(f, 96), table = uint64_t(load<int64_t>(f, pointStart));
  const uint32_t n = load<uint32_t>(f, table + 4);
  std::vector<uint32_t> counts, bytes;
  {
    laz::ArithmeticDecoder dec;
    const auto* d = reinterpret_cast<const uint8_t*>(f.data());
    dec.init(d + table + 8, d + f.size());
    laz::IntegerDecoder ic(32, 2);
    for (uint32_t i = 0; i < n; ++i) {
      counts.push_back(uint32_t(ic.decompress(dec, i ? int32_t(counts.back()) : 0, 0)));
      bytes.push_back(uint32_t(ic.decompress(dec, i ? int32_t(bytes.back()) : 0, 1)));
    }
  }
  ASSERT_EQ(n, 65u);
  auto rewrite = [&](std::vector<uint32_t> b, uint64_t declared) {
    std::string g = f.substr(0, table);
    std::vector<uint8_t> t(8);
    std::memcpy(t.data() + 4, &n, 4);
    laz::ArithmeticEncoder enc(t);
    laz::IntegerDecoder ic(32, 2);
    for (uint32_t i = 0; i < n; ++i) {
      ic.compress(enc, i ? int32_t(counts[i - 1]) : 0, int32_t(counts[i]), 0);
      ic.compress(enc, i ? int32_t(b[i - 1]) : 0, int32_t(b[i]), 1);
    }
    enc.done();
    g.append(reinterpret_cast<const char*>(t.data()), t.size());
    // The COPC hierarchy EVLR sat after the table and is gone with it: no EVLRs, so that only
    // the table speaks; and the declared count.
    store<uint32_t>(g, 243, 0);
    store<uint64_t>(g, 247, declared);
    store<uint32_t>(g, 107, uint32_t(declared));
    return g;
  };
  // Untouched but for the rewrite: every point.
  EXPECT_EQ(readLeniently(rewrite(bytes, 1065)).points, 1065u);
  std::vector<uint32_t> b = bytes;
  b[9] += 1u << 20;  // chunk 10 runs past the table
  uint64_t lost = 0;
  for (size_t i = 9; i < n; ++i) lost += counts[i];
  const LenientRead r = readLeniently(rewrite(b, 1065));
  EXPECT_EQ(r.unreadable, lost);
  EXPECT_EQ(r.points + r.unreadable, 1065u);
  // The header declares fewer points than the chunks list, and some are lost: still balanced.
  const LenientRead s = readLeniently(rewrite(b, 1000));
  EXPECT_EQ(s.points + s.unreadable, 1065u);
  EXPECT_TRUE(test::anyContains(s.warnings,
                                "header declares 1000 points but the LAZ chunk table "
                                "lists 1065"));
  // And more than they list: the missing ones are counted too.
  const LenientRead m = readLeniently(rewrite(bytes, 1100));
  EXPECT_EQ(m.points, 1065u);
  EXPECT_EQ(m.unreadable, 35u);
  EXPECT_NE(errorReading(rewrite(bytes, 1100)).reason().find("chunks hold 1065"),
            std::string::npos);
}

}  // namespace

// ---- converting ---------------------------------------------------------------------------------

#include "nestlight/octree/octree_reader.h"

namespace {

// The converter's output is a function of the points: LAZ and LAS of the same scan give the same
// octree, payload and hierarchy files byte for byte.
TEST(LazConvert, LazAndLasOfAutzenConvertToIdenticalOctrees) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  test::TempDir t;
  test::buildOctreeFrom(laz("autzen_trim.laz"), t.path() / "z", 5000);
  test::buildOctreeFrom(sharedData() / "scans/autzen_trim.las", t.path() / "l", 5000);
  for (const char* f : {"octree.bin", "hierarchy.bin"})
    EXPECT_TRUE(test::readFile((t.path() / "z" / f).string()) ==
                test::readFile((t.path() / "l" / f).string()))
        << f;
  OctreeReader z(t.path() / "z"), l(t.path() / "l");
  EXPECT_EQ(z.metadata().points, 110000u);
  EXPECT_EQ(z.metadata().accounting.input, l.metadata().accounting.input);
  EXPECT_EQ(z.metadata().accounting.duplicatesMerged, l.metadata().accounting.duplicatesMerged);
  EXPECT_GT(z.allNodes().size(), 10u);
  EXPECT_EQ(z.metadata().sources.at(0).format, "laz");
}

// `export -o x.laz` writes the records `export -o x.las` writes, compressed.
TEST(LazConvert, ExportToLazHoldsTheRecordsOfExportToLas) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  test::TempDir t;
  test::buildOctreeFrom(laz("autzen_trim.laz"), t.path() / "o", 20000);
  std::string out;
  ASSERT_EQ(test::runCli("export " + t.file("o") + " -o " + t.file("a.laz"), &out), 0) << out;
  ASSERT_EQ(test::runCli("export " + t.file("o") + " -o " + t.file("a.las"), &out), 0) << out;
  const Records z = records(t.file("a.laz")), l = records(t.file("a.las"));
  EXPECT_EQ(z.count(), 110000u);
  EXPECT_TRUE(z.bytes == l.bytes) << firstDifference(z, l);
  EXPECT_LT(std::filesystem::file_size(t.file("a.laz")),
            std::filesystem::file_size(t.file("a.las")) / 2);
  EXPECT_NE(
      test::runCli("export " + t.file("o") + " -o " + t.file("b.las") + " --format laz", &out), 0);
  EXPECT_NE(out.find("needs an output file ending in .laz"), std::string::npos) << out;
}

// A damaged LAZ read leniently: the accounting covers every declared point, the damaged chunk's
// as rejected, nothing counted twice.
TEST(LazConvert, LenientConversionCountsTheDamagedChunkAsRejected) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  std::string f = test::readFile(laz("autzen_trim.laz"));
  const LazLayout l = layoutOf(f);
  f[l.chunkStart(1) + 500] ^= 0x5A;  // damage chunk 2's stream
  f[l.chunkStart(1) + 501] ^= 0xA5;
  test::TempDir t;
  test::writeFile(t.file("d.laz"), f);
  std::string out;
  EXPECT_NE(
      test::runCli("convert " + t.file("d.laz") + " -o " + t.file("o") + " --progress quiet", &out),
      0);
  EXPECT_NE(out.find("chunk 2 of 3"), std::string::npos) << out;
  ASSERT_EQ(test::runCli(
                "convert " + t.file("d.laz") + " -o " + t.file("o") + " --lenient --progress quiet",
                &out),
            0)
      << out;
  OctreeReader r(t.path() / "o");
  const Accounting& a = r.metadata().accounting;
  EXPECT_EQ(a.input, 110000u);
  EXPECT_EQ(a.rejected.at(reject::kUnreadable), 50000u);
  EXPECT_TRUE(a.balanced());
  EXPECT_EQ(r.metadata().points + a.duplicatesMerged, 60000u);
  // The source says what it gave and what it could not: verify's balance holds.
  ASSERT_EQ(r.metadata().sources.size(), 1u);
  EXPECT_EQ(r.metadata().sources[0].points, 60000u);
  EXPECT_EQ(r.metadata().sources[0].unreadable, 50000u);
  VerifyReport v = verifyOctree(t.path() / "o");
  EXPECT_TRUE(v.ok()) << (v.failures.empty() ? "" : v.failures.front());
}

}  // namespace

// ---- two chunks at a time -----------------------------------------------------------------------

#include <random>

#include "laz/format.h"
#include "laz/writer.h"

namespace {

// The chunks of a LASzip 2 or 3 file with a fixed chunk size, as decoder jobs (outputs unset).
struct LazChunks {
  std::string file;
  laz::LaszipInfo info;
  std::vector<laz::ChunkDecoder::Job> jobs;
};

LazChunks chunksOf(const std::string& path) {
  LazChunks c;
  c.file = test::readFile(path);
  const std::string& f = c.file;
  const auto* d = reinterpret_cast<const uint8_t*>(f.data());
  const int format = uint8_t(f[104]) & 0x3F;  // without the compressed-data flag
  const uint16_t recordLength = load<uint16_t>(f, 105);
  uint64_t points = load<uint32_t>(f, 107);
  if (points == 0 && f[25] >= 4) points = load<uint64_t>(f, 247);
  size_t at = load<uint16_t>(f, 94);
  for (uint32_t v = 0, n = load<uint32_t>(f, 100); v < n; ++v) {
    const uint16_t length = load<uint16_t>(f, at + 20);
    if (f.compare(at + 2, 14, laz::kLaszipUserId) == 0 &&
        load<uint16_t>(f, at + 18) == laz::kLaszipRecordId) {
      EXPECT_EQ(laz::parseLaszipVlr(d + at + 54, length, format, recordLength, c.info), "");
    }
    at += 54 + length;
  }
  const LazLayout l = layoutOf(f);
  uint64_t left = points;
  for (size_t i = 0; i < l.bytes.size(); ++i) {
    const uint32_t n = uint32_t(std::min<uint64_t>(left, c.info.chunkSize));
    c.jobs.push_back({d + l.chunkStart(i), l.bytes[i], n, nullptr});
    left -= n;
  }
  EXPECT_EQ(left, 0u) << path;
  return c;
}

std::unique_ptr<laz::ChunkDecoder> decoderFor(const laz::LaszipInfo& info) {
  return info.compressor == laz::Compressor::LayeredChunked ? laz::makeLayeredDecoder(info)
                                                            : laz::makePointwiseDecoder(info);
}

// What decode() makes of a job: its records and bytes used, or its error.
struct Decoded {
  std::vector<uint8_t> records;
  laz::ChunkDecoder::Outcome outcome;
};
Decoded alone(laz::ChunkDecoder& dec, laz::ChunkDecoder::Job j, size_t recordSize) {
  Decoded r;
  r.records.assign(size_t(j.count) * recordSize, 0);
  j.out = r.records.data();
  try {
    r.outcome.used = dec.decode(j.data, j.size, j.count, j.out);
  } catch (const laz::DecodeError& e) {
    r.outcome.error = e;
  }
  return r;
}
std::pair<Decoded, Decoded> paired(laz::ChunkDecoder& dec, laz::ChunkDecoder::Job a,
                                   laz::ChunkDecoder::Job b, size_t recordSize) {
  std::pair<Decoded, Decoded> r;
  r.first.records.assign(size_t(a.count) * recordSize, 0);
  r.second.records.assign(size_t(b.count) * recordSize, 0);
  a.out = r.first.records.data();
  b.out = r.second.records.data();
  dec.decodePair(a, b, r.first.outcome, r.second.outcome);
  return r;
}

// Equal records (when intact) and equal outcomes: bytes used, or the same error at the same byte.
void expectSame(const Decoded& want, const Decoded& got, const std::string& what) {
  ASSERT_EQ(bool(want.outcome.error), bool(got.outcome.error))
      << what << ": " << (want.outcome.error ? want.outcome.error->what() : "")
      << (got.outcome.error ? got.outcome.error->what() : "");
  if (want.outcome.error) {
    EXPECT_STREQ(want.outcome.error->what(), got.outcome.error->what()) << what;
    EXPECT_EQ(want.outcome.error->offset, got.outcome.error->offset) << what;
    return;
  }
  EXPECT_EQ(want.outcome.used, got.outcome.used) << what;
  EXPECT_TRUE(want.records == got.records) << what;
}

// A LAZ of 120,000 format 3 records with 27 extra bytes (three chunks: 50,000, 50,000 and
// 20,000), compressed by our writer from the header of extrabytes.las and records that are in
// turn random and near copies of the one before, so that every field takes both the predicted
// and the surprising paths of its models.
std::string variedLaz(const test::TempDir& t) {
  std::string f = test::readFile(laz("extrabytes.las"));
  const uint32_t pointStart = load<uint32_t>(f, 96);
  const uint16_t recordLength = load<uint16_t>(f, 105);
  f.resize(pointStart);
  const uint32_t n = 120000;
  store<uint32_t>(f, 107, n);
  std::mt19937 rng(7);
  std::string rec(recordLength, '\0');
  for (uint32_t i = 0; i < n; ++i) {
    if (rng() % 2) {
      for (char& b : rec) b = char(rng());
    } else {
      for (int k = 0; k < 4; ++k) rec[rng() % recordLength] += char(1 + rng() % 3);
    }
    f += rec;
  }
  test::writeFile(t.file("varied.las"), f);
  laz::compressLas(t.file("varied.las"), t.file("varied.laz"), "varied.las");
  return t.file("varied.laz");
}

// Every pair of chunks (of equal and unequal lengths, a chunk with itself) decodes in lock step
// to what each decodes alone, for every item the files hold: POINT10, GPSTIME11, RGB12 and BYTE
// version 2, and the layered format 6 (whose decoder pairs one by one).
TEST(LazPairs, TwoChunksAtOnceDecodeAsEachAlone) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  test::TempDir t;
  const std::string varied = variedLaz(t);
  for (const std::string& path :
       {laz("point10.las.laz"), laz("point-color.las.laz"), laz("point-time.las.laz"),
        laz("point-color-time.las.laz"), laz("extrabytes.laz"), laz("autzen_trim.laz"),
        laz("1_4_w_evlr.laz"), varied}) {
    const LazChunks c = chunksOf(path);
    const std::string name = std::filesystem::path(path).filename().string();
    const size_t rs = c.info.recordSize();
    auto dec = decoderFor(c.info);
    std::vector<Decoded> want;
    for (const auto& j : c.jobs) want.push_back(alone(*dec, j, rs));
    for (size_t i = 0; i < c.jobs.size(); ++i)
      for (size_t k = 0; k < c.jobs.size(); ++k) {
        const auto got = paired(*dec, c.jobs[i], c.jobs[k], rs);
        const std::string what = name + " chunks " + std::to_string(i) + "+" + std::to_string(k);
        expectSame(want[i], got.first, what + " (first)");
        expectSame(want[k], got.second, what + " (second)");
        // Intact pointwise chunks really ran in lock step (a stream that runs dry would fall
        // back to one by one and hide a lane that decodes the wrong stream).
        const bool pointwise = c.info.compressor != laz::Compressor::LayeredChunked;
        EXPECT_EQ(got.first.outcome.lockstep, pointwise) << what;
        EXPECT_EQ(got.second.outcome.lockstep, pointwise) << what;
      }
    // The decoder is still good for one chunk at a time afterwards.
    expectSame(want[0], alone(*dec, c.jobs[0], rs), name + " after pairs");
  }
}

// A damaged chunk beside an intact one: the intact one decodes, the damaged one fails (or
// decodes to garbage) exactly as it would alone, with the same message and byte, either side.
TEST(LazPairs, ADamagedChunkFailsInAPairAsItWouldAlone) {
  NL_REQUIRE_SHARED("laz/autzen_trim.laz");
  const LazChunks c = chunksOf(laz("autzen_trim.laz"));
  ASSERT_EQ(c.jobs.size(), 3u);
  const size_t rs = c.info.recordSize();
  auto dec = decoderFor(c.info);
  std::vector<std::vector<uint8_t>> damagedBytes;
  std::vector<laz::ChunkDecoder::Job> damaged;
  const laz::ChunkDecoder::Job good = c.jobs[1];
  damaged.push_back({good.data, good.size / 2, good.count, nullptr});  // truncated midway
  damaged.push_back({good.data, 20, good.count, nullptr});  // shorter than the first record
  damaged.push_back({good.data, good.size - 3, good.count, nullptr});  // runs dry at the end
  for (size_t flip : {size_t(500), good.size / 2}) {  // bytes changed: garbage or an error
    damagedBytes.emplace_back(good.data, good.data + good.size);
    damagedBytes.back()[flip] ^= 0x5A;
    damagedBytes.back()[flip + 1] ^= 0xA5;
  }
  for (const auto& b : damagedBytes) damaged.push_back({b.data(), b.size(), good.count, nullptr});
  size_t errors = 0;
  for (size_t d = 0; d < damaged.size(); ++d)
    for (size_t other : {size_t(0), size_t(2)}) {  // a longer and a shorter intact chunk
      const Decoded bad = alone(*dec, damaged[d], rs);
      const Decoded intact = alone(*dec, c.jobs[other], rs);
      errors += bool(bad.outcome.error);
      const std::string what =
          "damage " + std::to_string(d) + " with chunk " + std::to_string(other);
      auto got = paired(*dec, damaged[d], c.jobs[other], rs);
      expectSame(bad, got.first, what + " (damaged first)");
      expectSame(intact, got.second, what + " (intact second)");
      got = paired(*dec, c.jobs[other], damaged[d], rs);
      expectSame(intact, got.first, what + " (intact first)");
      expectSame(bad, got.second, what + " (damaged second)");
    }
  EXPECT_GE(errors, 6u);  // the three cut chunks fail beside both partners
}

}  // namespace

// ---- the layered encoder (LAZ output of formats 6-8) --------------------------------------------

namespace {

// LASzip's own chunk of 1_4_w_evlr.laz (format 6) is what our encoder makes of the LAS twin's
// records, bit for bit: the same models, the same choices, the same dropped layers.
TEST(LazLayeredWriter, TheChunkOfTheLas14TwinIsLaszipsOwnByteForByte) {
  NL_REQUIRE_SHARED("laz/1_4_w_evlr.laz");
  const LazChunks c = chunksOf(laz("1_4_w_evlr.laz"));
  ASSERT_EQ(c.jobs.size(), 1u);
  const std::string las = test::readFile(laz("1_4_w_evlr.las"));
  const auto* records = reinterpret_cast<const uint8_t*>(las.data()) + load<uint32_t>(las, 96);
  std::vector<uint8_t> chunk;
  laz::makeLayeredEncoder(c.info)->encode(records, c.jobs[0].count, chunk);
  ASSERT_EQ(chunk.size(), c.jobs[0].size);
  EXPECT_TRUE(std::equal(chunk.begin(), chunk.end(), c.jobs[0].data));
}

// Records of format 6, 7 or 8 (with extra bytes), in turn random and near copies of the one
// before, with scanner channel switches, GPS times that step, jump and return to earlier
// sequences: every context switch and coding path of the layered items.
std::vector<uint8_t> variedRecords14(size_t recordSize, size_t n, uint32_t seed) {
  std::vector<uint8_t> out(n * recordSize);
  std::mt19937 rng(seed);
  std::vector<uint8_t> rec(recordSize);
  double t[2] = {1e8, 3e8};
  int sequence = 0;
  for (size_t i = 0; i < n; ++i) {
    if (rng() % 4 == 0) {
      for (auto& b : rec) b = uint8_t(rng());
    } else {
      for (int k = 0; k < 3; ++k) rec[rng() % recordSize] += uint8_t(1 + rng() % 3);
      uint32_t x;
      std::memcpy(&x, rec.data(), 4);
      x += rng() % 100;
      std::memcpy(rec.data(), &x, 4);
      if (rng() % 3 == 0) rec[14] = uint8_t((rec[14] & 0xF0) | (((rec[14] & 15) + 1) & 15));
      if (rng() % 50 == 0) rec[15] = uint8_t((rec[15] & 0xCF) | ((rng() % 4) << 4));
      if (rng() % 300 == 0) sequence ^= 1;  // back to the other time sequence
      t[sequence] += rng() % 2 ? (rng() % 1000) * 1e-6 : 0.0;
      if (rng() % 500 == 0) t[sequence] += 1e7;  // beyond 32 bits of difference
      std::memcpy(rec.data() + 22, &t[sequence], 8);
    }
    std::memcpy(out.data() + i * recordSize, rec.data(), recordSize);
  }
  return out;
}

// Chunks of every layered item the encoder writes decode (with the decoder that matches LASzip's
// files) to the records they were made of: 30,000 points, one point and two points; a field
// that never changes leaves its layer empty.
TEST(LazLayeredWriter, ChunksOfFormats6To8RoundTripThroughTheDecoder) {
  struct Case {
    const char* name;
    std::vector<laz::Item> items;
  };
  const std::vector<Case> cases = {
      {"format 6", {{laz::ItemType::Point14, 30, 3}}},
      {"format 7", {{laz::ItemType::Point14, 30, 3}, {laz::ItemType::Rgb14, 6, 3}}},
      {"format 8", {{laz::ItemType::Point14, 30, 3}, {laz::ItemType::RgbNir14, 8, 3}}},
      {"format 7 + 5 extra bytes",
       {{laz::ItemType::Point14, 30, 3},
        {laz::ItemType::Rgb14, 6, 3},
        {laz::ItemType::Byte14, 5, 3}}}};
  uint32_t seed = 1;
  for (const Case& k : cases) {
    laz::LaszipInfo info;
    info.compressor = laz::Compressor::LayeredChunked;
    info.chunkSize = 50000;
    info.items = k.items;
    const size_t rs = info.recordSize();
    std::vector<uint8_t> records = variedRecords14(rs, 30000, seed++);
    auto enc = laz::makeLayeredEncoder(info);
    auto dec = laz::makeLayeredDecoder(info);
    for (size_t n : {size_t(30000), size_t(1), size_t(2)}) {
      std::vector<uint8_t> chunk, back(n * rs);
      enc->encode(records.data(), n, chunk);
      EXPECT_EQ(dec->decode(chunk.data(), chunk.size(), uint32_t(n), back.data()), chunk.size())
          << k.name << ", " << n << " points";
      EXPECT_TRUE(std::equal(back.begin(), back.end(), records.begin()))
          << k.name << ", " << n << " points";
    }
    // Class, user data and the extra bytes held still: their layers are empty, and the
    // decoder keeps the first point's values.
    for (size_t p = 0; p < 30000; ++p) {
      records[p * rs + 16] = 7;
      records[p * rs + 17] = 9;
      for (size_t b = 36; b < rs && rs == 41; ++b) records[p * rs + b] = 3;
    }
    std::vector<uint8_t> chunk, back(30000 * rs);
    enc->encode(records.data(), 30000, chunk);
    EXPECT_EQ(load<uint32_t>(std::string(chunk.begin(), chunk.end()), rs + 4 + 4 * 2), 0u)
        << k.name << ": classification layer";
    EXPECT_EQ(load<uint32_t>(std::string(chunk.begin(), chunk.end()), rs + 4 + 4 * 6), 0u)
        << k.name << ": user data layer";
    dec->decode(chunk.data(), chunk.size(), 30000, back.data());
    EXPECT_TRUE(back == records) << k.name << " with fields held still";
  }
}

// export-style LAZ output of LAS 1.4 format 7 and 8 files (three chunks) reads back to the
// records of the LAS file it was made from.
TEST(LazLayeredWriter, Las14FilesOfFormats7And8CompressAndReadBack) {
  NL_REQUIRE_SHARED("laz/1_4_w_evlr.las");
  for (const int pf : {7, 8}) {
    const size_t rs = pf == 7 ? 36 : 38, n = 120000;
    std::string f = test::readFile(laz("1_4_w_evlr.las"));
    const uint32_t pointStart = load<uint32_t>(f, 96);
    f.resize(pointStart);
    f[104] = char(pf);
    store<uint16_t>(f, 105, uint16_t(rs));
    store<uint64_t>(f, 235, 0);  // no EVLRs
    store<uint32_t>(f, 243, 0);
    store<uint32_t>(f, 107, 0);  // formats 6+ keep the legacy counts zero
    for (size_t at = 111; at < 131; at += 4) store<uint32_t>(f, at, 0);
    store<uint64_t>(f, 247, n);
    for (size_t at = 255; at < 375; at += 8) store<uint64_t>(f, at, 0);
    const std::vector<uint8_t> recs = variedRecords14(rs, n, uint32_t(pf));
    f.append(reinterpret_cast<const char*>(recs.data()), recs.size());
    test::TempDir t;
    test::writeFile(t.file("in.las"), f);
    laz::compressLas(t.file("in.las"), t.file("out.laz"), "in.las");
    const Records plain = records(t.file("in.las"));
    const Records back = records(t.file("out.laz"));
    EXPECT_EQ(back.header.details["laszip"]["compressor"], "layered chunked")
        << back.header.details.dump();
    EXPECT_EQ(back.header.details["laszip"]["chunks"], 3);
    ASSERT_EQ(back.count(), n);
    EXPECT_TRUE(back.bytes == plain.bytes)
        << "format " << pf << ": " << firstDifference(plain, back);
    EXPECT_LT(std::filesystem::file_size(t.file("out.laz")), f.size());
  }
}

}  // namespace

namespace {

// The LAS writer's LAZ output of points that need LAS 1.4 (this twin's 16-bit scan angles) is a
// layered LAZ of format 6 that reads back to the same points and attributes.
TEST(LazLayeredWriter, WriterOutputOfLas14PointsReadsBack) {
  NL_REQUIRE_SHARED("laz/1_4_w_evlr.las");
  test::TempDir t;
  auto r = openReader(laz("1_4_w_evlr.las"));
  const std::string out = t.file("a.laz");
  {
    auto w = createWriter(out, r->header());
    PointBatch b;
    while (r->read(b, 300)) w->write(b);
    w->close();
  }
  const Records back = records(out);
  EXPECT_EQ(back.header.details["laszip"]["compressor"], "layered chunked");
  auto a = openReader(laz("1_4_w_evlr.las"));
  auto z = openReader(out);
  const test::Points pa = test::readAll(*a, 1000), pz = test::readAll(*z, 1000);
  ASSERT_EQ(pz.size(), 1000u);
  EXPECT_TRUE(pa.xyz == pz.xyz);
  ASSERT_EQ(a->header().layout.stride(), z->header().layout.stride());
  EXPECT_TRUE(pa.attrs == pz.attrs);
}

}  // namespace

// ---- headers that lie and chunk tables that are damaged, on generated files --------------------

namespace {

// `n` generated points written as LAZ by the LAS writer: LASzip 2's pointwise chunks (LAS 1.2,
// format 1) or, with `layered`, LASzip 3's layered chunks (16-bit scan angles need format 6).
std::string generatedLaz(const test::TempDir& t, uint32_t n, bool layered) {
  SourceHeader h;
  h.format = "test";
  std::vector<Attribute> a = {{"intensity", ScalarType::U16, 1, ""},
                              {"gps_time", ScalarType::F64, 1, ""}};
  if (layered) a.push_back({"scan_angle", ScalarType::I16, 1, ""});
  h.layout = PointLayout(a);
  h.scale = Vec3d{0.001, 0.001, 0.001};
  const std::string path = t.file(layered ? "layered.laz" : "pointwise.laz");
  auto w = createWriter(path, h);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 50);
  for (uint32_t first = 0; first < n; first += 7000) {
    PointBatch b;
    const uint32_t m = std::min<uint32_t>(7000, n - first);
    for (uint32_t i = 0; i < m; ++i) {
      b.xyz.insert(b.xyz.end(), {u(rng), u(rng), u(rng) * 0.1});
      const uint16_t intensity = uint16_t(rng());
      const double time = 1e5 + (first + i) * 1e-4;
      const int16_t angle = int16_t(int(rng() % 6000) - 3000);
      const size_t at = b.attrs.size();
      b.attrs.resize(at + h.layout.stride());
      std::memcpy(&b.attrs[at], &intensity, 2);
      std::memcpy(&b.attrs[at + 2], &time, 8);
      if (layered) std::memcpy(&b.attrs[at + 10], &angle, 2);
    }
    w->write(b);
  }
  w->close();
  return test::readFile(path);
}

// The point count fields of a LAS header: the legacy 32-bit one, and LAS 1.4's 64-bit one.
std::string withDeclared(std::string f, uint64_t declared) {
  if ((load<uint8_t>(f, 104) & 0x3F) < 6) store<uint32_t>(f, 107, uint32_t(declared));
  if (load<uint8_t>(f, 25) >= 4) store<uint64_t>(f, 247, declared);
  return f;
}

std::vector<uint8_t> recordsOf(const std::string& f, ReadOptions o = {}) {
  std::vector<uint8_t> out;
  readLasRecords(
      memorySource("f.laz", std::vector<uint8_t>(f.begin(), f.end())), o,
      [&](const uint8_t* p, size_t n, size_t length) { out.insert(out.end(), p, p + n * length); },
      nullptr, nullptr);
  return out;
}

// A header that declares fewer points than the chunks hold (a count field edited, or written
// before the last points): every point the chunks hold is read, and the difference is said, with
// or without --lenient. Fixed-size chunks: all but the last are full, and the last one's count is
// its own (layered) or found by decoding it to the end of its bytes (pointwise).
TEST(LazHeader, ACountUnderstatedByTheHeaderReadsEveryPointTheChunksHold) {
  test::TempDir t;
  for (bool layered : {false, true}) {
    SCOPED_TRACE(layered ? "layered" : "pointwise");
    const std::string f = generatedLaz(t, 110000, layered);
    const std::vector<uint8_t> want = recordsOf(f);
    ASSERT_EQ(want.size() % 110000, 0u);
    for (uint64_t declared : {uint64_t(1), uint64_t(50000), uint64_t(100001), uint64_t(109999)}) {
      SCOPED_TRACE(declared);
      const std::string lie = withDeclared(f, declared);
      const LenientRead r = readLeniently(lie);
      EXPECT_EQ(r.points, 110000u);
      EXPECT_EQ(r.unreadable, 0u);
      EXPECT_TRUE(test::anyContains(r.warnings, "header declares " + std::to_string(declared) +
                                                    " points but the 3 LAZ chunks hold 110000"))
          << (r.warnings.empty() ? "no warning" : r.warnings[0]);
      EXPECT_TRUE(recordsOf(lie) == want) << "strict reading gives the same points";
    }
    // An honest header: no warning.
    EXPECT_TRUE(readLeniently(f).warnings.empty());
  }
}

// One wrong byte in the chunk table garbles every entry after it, and a table cut short is only
// partly there: read leniently, the chunks are found one after the other instead (each starts
// where the previous one's stream ended), and every point is recovered; strict reading fails,
// naming the table.
TEST(LazDamage, ADamagedChunkTableIsReadAroundByFindingTheChunks) {
  test::TempDir t;
  for (bool layered : {false, true}) {
    SCOPED_TRACE(layered ? "layered" : "pointwise");
    const std::string f = generatedLaz(t, 110000, layered);
    const std::vector<uint8_t> want = recordsOf(f);
    const uint64_t table = uint64_t(load<int64_t>(f, load<uint32_t>(f, 96)));
    for (size_t at : {size_t(8), size_t(9), size_t(10), size_t(12)}) {
      if (table + at >= f.size()) continue;
      SCOPED_TRACE("byte " + std::to_string(at) + " of the table flipped");
      std::string bad = f;
      bad[table + at] = char(~uint8_t(bad[table + at]));
      const LenientRead r = readLeniently(bad);
      EXPECT_EQ(r.points, 110000u);
      EXPECT_EQ(r.unreadable, 0u);
      ReadOptions o;
      o.lenient = true;
      EXPECT_TRUE(recordsOf(bad, o) == want);
      EXPECT_FALSE(r.warnings.empty());
      EXPECT_NE(errorReading(bad).what(), std::string());
    }
    const std::string cut = f.substr(0, table + 9);
    const LenientRead c = readLeniently(cut);
    EXPECT_EQ(c.points, 110000u);
    EXPECT_TRUE(test::anyContains(c.warnings, "ends inside the entry of chunk"))
        << (c.warnings.empty() ? "no warning" : c.warnings[0]);
    EXPECT_NE(errorReading(cut).reason().find("ends inside the entry of chunk"), std::string::npos);
  }
}

}  // namespace

namespace {

// A COPC file whose hierarchy claims more points for a chunk than the chunk holds, read through
// the hierarchy (its chunk table offset broken): the conversion fails part way, on two threads,
// naming the file and the chunk, and frees what was in flight (under ASan the child process's
// leak check would report "LeakSanitizer"; a 5.7 MB leak once came from this path).
TEST(LazConvert, ACopcHierarchyClaimingMorePointsFailsCleanly) {
  NL_REQUIRE_SHARED("laz/simple.copc.laz");
  test::TempDir t;
  std::string f = test::readFile(laz("simple.copc.laz"));
  const uint32_t pointStart = load<uint32_t>(f, 96);
  const uint64_t table = uint64_t(load<int64_t>(f, pointStart));
  // The chunk table's entries (variable-size chunks: count, then bytes), to find the hierarchy's.
  std::vector<uint32_t> counts, bytes;
  {
    laz::ArithmeticDecoder dec;
    const auto* d = reinterpret_cast<const uint8_t*>(f.data());
    dec.init(d + table + 8, d + f.size());
    laz::IntegerDecoder ic(32, 2);
    for (uint32_t i = 0, n = load<uint32_t>(f, table + 4); i < n; ++i) {
      counts.push_back(uint32_t(ic.decompress(dec, i ? int32_t(counts.back()) : 0, 0)));
      bytes.push_back(uint32_t(ic.decompress(dec, i ? int32_t(bytes.back()) : 0, 1)));
    }
  }
  // A hierarchy entry is a key (4 x int32), the chunk's offset (uint64), bytes and points
  // (int32 each): find the entry of the middle chunk by its offset and size, and inflate it.
  uint64_t at = pointStart + 8;
  const size_t middle = counts.size() / 2;
  for (size_t i = 0; i < middle; ++i) at += bytes[i];
  std::string needle(12, '\0');
  std::memcpy(needle.data(), &at, 8);
  std::memcpy(needle.data() + 8, &bytes[middle], 4);
  const size_t entry = f.find(needle, table);
  ASSERT_NE(entry, std::string::npos) << "the hierarchy entry of chunk " << middle + 1;
  ASSERT_EQ(load<int32_t>(f, entry + 12), int32_t(counts[middle]));
  store<int32_t>(f, entry + 12, int32_t(counts[middle] + 5000));
  store<int64_t>(f, pointStart, int64_t(f.size()) + 1000);  // read the chunks from the hierarchy
  test::writeFile(t.file("claims.copc.laz"), f);
  std::string out;
  EXPECT_NE(test::runCli("convert " + t.file("claims.copc.laz") + " -o " + t.file("o") +
                             " --threads 2 --progress quiet",
                         &out),
            0);
  EXPECT_NE(out.find("claims.copc.laz"), std::string::npos) << out;
  EXPECT_NE(out.find("chunk " + std::to_string(middle + 1)), std::string::npos) << out;
  EXPECT_EQ(out.find("LeakSanitizer"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(t.file("o") + "/metadata.json"));
}

}  // namespace
