// LAS reader and writer: every point format, hard headers, real scans.
//
// Synthetic files are encoded here by hand from the LAS 1.4 R15 tables, independently of the
// reader, so that a shared misreading of the specification cannot pass unnoticed.
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <optional>
#include <random>

#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight {
namespace {

using test::TempDir;

template <typename T>
void put(std::string& s, size_t at, T v) {
  if (s.size() < at + sizeof(T)) s.resize(at + sizeof(T), '\0');
  std::memcpy(&s[at], &v, sizeof(T));
}

std::vector<uint8_t> toBytes(const std::string& s) {
  return {s.begin(), s.end()};
}

// ---- Hand encoding of LAS files -------------------------------------------------------------

constexpr size_t kBase[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
bool legacy(int pf) {
  return pf < 6;
}
bool gps(int pf) {
  return pf != 0 && pf != 2;
}
bool rgb(int pf) {
  return pf == 2 || pf == 3 || pf == 5 || pf == 7 || pf == 8 || pf == 10;
}
bool nir(int pf) {
  return pf == 8 || pf == 10;
}
bool wave(int pf) {
  return pf == 4 || pf == 5 || pf == 9 || pf == 10;
}

struct RawPoint {
  int32_t X, Y, Z;
  uint16_t intensity;
  uint8_t ret, nret, sdf, edge, cls, flags, channel;
  int8_t rank;
  int16_t angle;
  uint8_t user;
  uint16_t psid;
  double gps;
  std::array<uint16_t, 3> rgb;
  uint16_t nir;
  uint8_t wpIndex;
  uint64_t wpOffset;
  uint32_t wpSize;
  float wLocation;
  std::array<float, 3> wXyz;
  // Extra bytes: "height" float, "pair" int16 x2 (deprecated type 14), 3 undocumented bytes.
  float height;
  std::array<int16_t, 2> pair;
  std::array<uint8_t, 3> raw;
};
constexpr size_t kExtraBytes = 4 + 4 + 3;

// Values that exercise every bit of every field the format has.
RawPoint makePoint(int pf, int i) {
  const bool old = legacy(pf);
  RawPoint p{};
  p.X = -50000 + 1237 * i;
  p.Y = 2000000 + 7 * i * i;
  p.Z = -31 * i;
  p.intensity = static_cast<uint16_t>(1000 + 1601 * i);
  p.ret = static_cast<uint8_t>(1 + i % (old ? 7 : 15));
  p.nret = static_cast<uint8_t>(1 + (5 * i) % (old ? 7 : 15));
  p.sdf = i & 1;
  p.edge = (i >> 1) & 1;
  p.cls = static_cast<uint8_t>(old ? i % 32 : (37 * i) % 256);
  p.flags = static_cast<uint8_t>(old ? i % 8 : i % 16);
  p.channel = i % 4;
  p.rank = static_cast<int8_t>(-90 + 4 * i);
  p.angle = static_cast<int16_t>(-30000 + 1500 * i);
  p.user = static_cast<uint8_t>(7 * i + 3);
  p.psid = static_cast<uint16_t>(65535 - 11 * i);
  p.gps = 245379.39843682514 + 0.1 * i;
  p.rgb = {static_cast<uint16_t>(1601 * i), static_cast<uint16_t>(65535 - 3 * i),
           static_cast<uint16_t>(i * i)};
  p.nir = static_cast<uint16_t>(40000 + i);
  p.wpIndex = static_cast<uint8_t>(i);
  p.wpOffset = 0x0102030405060708ull + i;
  p.wpSize = 1000 + i;
  p.wLocation = 0.5f * i;
  p.wXyz = {1.f / (i + 1), -2.5f * i, 1e-3f * i};
  p.height = 0.25f * i - 3;
  p.pair = {static_cast<int16_t>(-100 * i), static_cast<int16_t>(200 * i)};
  p.raw = {static_cast<uint8_t>(i), static_cast<uint8_t>(255 - i), 0x5A};
  return p;
}

std::string encodeRecord(int pf, const RawPoint& p) {
  std::string r(kBase[pf] + kExtraBytes, '\0');
  put(r, 0, p.X), put(r, 4, p.Y), put(r, 8, p.Z), put(r, 12, p.intensity);
  if (legacy(pf)) {
    r[14] = static_cast<char>(p.ret | p.nret << 3 | p.sdf << 6 | p.edge << 7);
    r[15] = static_cast<char>(p.cls | p.flags << 5);
    put(r, 16, p.rank), put(r, 17, p.user), put(r, 18, p.psid);
    if (gps(pf)) put(r, 20, p.gps);
    if (rgb(pf)) put(r, gps(pf) ? 28 : 20, p.rgb);
    if (wave(pf)) put(r, pf == 4 ? 28 : 34, p.wpIndex);
  } else {
    r[14] = static_cast<char>(p.ret | p.nret << 4);
    r[15] = static_cast<char>(p.flags | p.channel << 4 | p.sdf << 6 | p.edge << 7);
    put(r, 16, p.cls), put(r, 17, p.user), put(r, 18, p.angle), put(r, 20, p.psid);
    put(r, 22, p.gps);
    if (rgb(pf)) put(r, 30, p.rgb);
    if (nir(pf)) put(r, 36, p.nir);
    if (wave(pf)) put(r, pf == 9 ? 30 : 38, p.wpIndex);
  }
  if (wave(pf)) {
    const size_t w = kBase[pf] - 29;
    put(r, w + 1, p.wpOffset), put(r, w + 9, p.wpSize), put(r, w + 13, p.wLocation);
    put(r, w + 17, p.wXyz);
  }
  put(r, kBase[pf], p.height), put(r, kBase[pf] + 4, p.pair), put(r, kBase[pf] + 8, p.raw);
  return r;
}

std::string vlr(const std::string& user, uint16_t id, const std::string& data) {
  std::string v(54, '\0');
  std::memcpy(&v[2], user.data(), std::min<size_t>(16, user.size()));
  put(v, 18, id), put(v, 20, static_cast<uint16_t>(data.size()));
  return v + data;
}
std::string evlr(const std::string& user, uint16_t id, const std::string& data) {
  std::string v(60, '\0');
  std::memcpy(&v[2], user.data(), std::min<size_t>(16, user.size()));
  put(v, 18, id), put(v, 20, static_cast<uint64_t>(data.size()));
  return v + data;
}
std::string extraBytesDescriptor(const std::string& name, uint8_t type, uint8_t options,
                                 std::optional<double> scale = {}) {
  std::string d(192, '\0');
  d[2] = static_cast<char>(type);
  d[3] = static_cast<char>(options | (scale ? 8 : 0));
  std::memcpy(&d[4], name.data(), std::min<size_t>(32, name.size()));
  if (scale) put(d, 112, *scale);
  return d;
}

struct LasFile {
  int minor = 2;
  int pf = 0;
  uint16_t recordLength = 0;  // 0: from the records
  std::array<double, 3> scale{0.01, 0.01, 0.01}, offset{1000, 2000, -10};
  std::vector<std::string> vlrs, records, evlrs;
  std::optional<uint64_t> declared;
  std::string trailing;  // bytes between the points and the EVLRs

  std::string bytes() const {
    const size_t hs = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
    std::string s(hs, '\0');
    std::memcpy(&s[0], "LASF", 4);
    s[24] = 1, s[25] = static_cast<char>(minor);
    std::memcpy(&s[26], "nestlight test", 14);
    put(s, 94, static_cast<uint16_t>(hs));
    std::string v;
    for (const auto& x : vlrs) v += x;
    put(s, 96, static_cast<uint32_t>(hs + v.size()));
    put(s, 100, static_cast<uint32_t>(vlrs.size()));
    s[104] = static_cast<char>(pf);
    const uint16_t rl = recordLength      ? recordLength
                        : records.empty() ? static_cast<uint16_t>(kBase[pf])
                                          : static_cast<uint16_t>(records[0].size());
    put(s, 105, rl);
    const uint64_t n = declared.value_or(records.size());
    if (pf < 6) put(s, 107, static_cast<uint32_t>(n));
    for (int a = 0; a < 3; ++a) put(s, 131 + 8 * a, scale[a]), put(s, 155 + 8 * a, offset[a]);
    std::string points;
    for (const auto& r : records) points += r;
    if (minor >= 4) {
      if (!evlrs.empty())
        put(s, 235, static_cast<uint64_t>(hs + v.size() + points.size() + trailing.size()));
      put(s, 243, static_cast<uint32_t>(evlrs.size()));
      put(s, 247, n);
    }
    s += v + points + trailing;
    for (const auto& x : evlrs) s += x;
    return s;
  }
};

// A file of `n` points of format `pf` with the test's three extra-bytes attributes.
LasFile makeFile(int pf, int n) {
  LasFile f;
  f.pf = pf;
  f.minor = pf >= 6 ? 4 : std::min(pf, 3);  // 1.0 ... 1.3 for the legacy formats
  f.vlrs.push_back(
      vlr("LASF_Spec", 4,
          extraBytesDescriptor("height", 9, 0, 0.01) + extraBytesDescriptor("pair", 14, 0)));
  for (int i = 0; i < n; ++i) f.records.push_back(encodeRecord(pf, makePoint(pf, i)));
  return f;
}

// ---- Reading helpers ------------------------------------------------------------------------

struct AllPoints {
  PointLayout layout;
  std::vector<double> xyz;
  std::vector<uint8_t> attrs;
  size_t size() const { return xyz.size() / 3; }
  double get(const std::string& name, size_t i, int component = 0) const {
    const int a = layout.find(name);
    EXPECT_GE(a, 0) << name;
    if (a < 0) return NAN;
    const size_t at =
        i * layout.stride() + layout.offset(a) + component * scalarSize(layout[a].type);
    return loadAsDouble(layout[a].type, attrs.data() + at);
  }
  // For 64-bit integers, which a double cannot hold exactly.
  template <typename T>
  T raw(const std::string& name, size_t i) const {
    const int a = layout.find(name);
    EXPECT_GE(a, 0) << name;
    T v{};
    if (a >= 0) std::memcpy(&v, attrs.data() + i * layout.stride() + layout.offset(a), sizeof v);
    return v;
  }
};

AllPoints readLasPoints(PointReader& r, size_t batchSize = 17) {
  AllPoints all;
  all.layout = r.header().layout;
  PointBatch b;
  while (r.read(b, batchSize)) {
    EXPECT_EQ(b.attrs.size(), b.size() * all.layout.stride());
    all.xyz.insert(all.xyz.end(), b.xyz.begin(), b.xyz.end());
    all.attrs.insert(all.attrs.end(), b.attrs.begin(), b.attrs.end());
  }
  return all;
}

std::unique_ptr<PointReader> openBytes(const std::string& bytes, const ReadOptions& o = {},
                                       const std::string& name = "test.las") {
  return openLas(memorySource(name, toBytes(bytes)), o);
}

// Copies `r` into a LAS file at `path` with the writer.
void copyTo(PointReader& r, const std::string& path, size_t batchSize = 16) {
  auto w = createLasWriter(path, r.header());
  PointBatch b;
  while (r.read(b, batchSize)) w->write(b);
  w->close();
}

struct Expected {
  const char* name;
  ScalarType type;
  uint32_t components;
};

std::vector<Expected> expectedLayout(int pf) {
  std::vector<Expected> e = {
      {"intensity", ScalarType::U16, 1},          {"return_number", ScalarType::U8, 1},
      {"number_of_returns", ScalarType::U8, 1},   {"scan_direction_flag", ScalarType::U8, 1},
      {"edge_of_flight_line", ScalarType::U8, 1}, {"classification", ScalarType::U8, 1},
      {"classification_flags", ScalarType::U8, 1}};
  if (legacy(pf)) {
    e.push_back({"scan_angle_rank", ScalarType::I8, 1});
  } else {
    e.push_back({"scanner_channel", ScalarType::U8, 1});
    e.push_back({"scan_angle", ScalarType::I16, 1});
  }
  e.push_back({"user_data", ScalarType::U8, 1});
  e.push_back({"point_source_id", ScalarType::U16, 1});
  if (gps(pf)) e.push_back({"gps_time", ScalarType::F64, 1});
  if (rgb(pf)) e.push_back({"rgb", ScalarType::U16, 3});
  if (nir(pf)) e.push_back({"nir", ScalarType::U16, 1});
  if (wave(pf)) {
    e.push_back({"wavepacket_index", ScalarType::U8, 1});
    e.push_back({"wavepacket_offset", ScalarType::U64, 1});
    e.push_back({"wavepacket_size", ScalarType::U32, 1});
    e.push_back({"waveform_location", ScalarType::F32, 1});
    e.push_back({"waveform_xyz", ScalarType::F32, 3});
  }
  e.push_back({"height", ScalarType::F32, 1});
  e.push_back({"pair", ScalarType::I16, 2});
  e.push_back({"extra_bytes", ScalarType::U8, 3});
  return e;
}

void expectPointsMatch(int pf, const AllPoints& all, int n) {
  ASSERT_EQ(all.size(), static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    SCOPED_TRACE("point " + std::to_string(i));
    const RawPoint p = makePoint(pf, i);
    EXPECT_EQ(all.xyz[3 * i + 0], p.X * 0.01 + 1000);
    EXPECT_EQ(all.xyz[3 * i + 1], p.Y * 0.01 + 2000);
    EXPECT_EQ(all.xyz[3 * i + 2], p.Z * 0.01 - 10);
    EXPECT_EQ(all.get("intensity", i), p.intensity);
    EXPECT_EQ(all.get("return_number", i), p.ret);
    EXPECT_EQ(all.get("number_of_returns", i), p.nret);
    EXPECT_EQ(all.get("scan_direction_flag", i), p.sdf);
    EXPECT_EQ(all.get("edge_of_flight_line", i), p.edge);
    EXPECT_EQ(all.get("classification", i), p.cls);
    EXPECT_EQ(all.get("classification_flags", i), p.flags);
    if (legacy(pf)) {
      EXPECT_EQ(all.get("scan_angle_rank", i), p.rank);
    } else {
      EXPECT_EQ(all.get("scanner_channel", i), p.channel);
      EXPECT_EQ(all.get("scan_angle", i), p.angle);
    }
    EXPECT_EQ(all.get("user_data", i), p.user);
    EXPECT_EQ(all.get("point_source_id", i), p.psid);
    if (gps(pf)) {
      EXPECT_EQ(all.get("gps_time", i), p.gps);
    }
    if (rgb(pf)) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(all.get("rgb", i, c), p.rgb[c]);
    }
    if (nir(pf)) {
      EXPECT_EQ(all.get("nir", i), p.nir);
    }
    if (wave(pf)) {
      EXPECT_EQ(all.get("wavepacket_index", i), p.wpIndex);
      EXPECT_EQ(all.raw<uint64_t>("wavepacket_offset", i), p.wpOffset);
      EXPECT_EQ(all.get("wavepacket_size", i), p.wpSize);
      EXPECT_EQ(all.get("waveform_location", i), p.wLocation);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(all.get("waveform_xyz", i, c), p.wXyz[c]);
    }
    EXPECT_EQ(all.get("height", i), p.height);
    for (int c = 0; c < 2; ++c) EXPECT_EQ(all.get("pair", i, c), p.pair[c]);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(all.get("extra_bytes", i, c), p.raw[c]);
  }
}

// ---- Reader ---------------------------------------------------------------------------------

TEST(LasReader, DecodesEveryPointFormat) {
  constexpr int kPoints = 40;
  for (int pf = 0; pf <= 10; ++pf) {
    SCOPED_TRACE("point format " + std::to_string(pf));
    auto r = openBytes(makeFile(pf, kPoints).bytes());
    const SourceHeader& h = r->header();
    EXPECT_EQ(h.format, "las");
    EXPECT_EQ(h.declaredPoints, uint64_t(kPoints));
    EXPECT_EQ(h.details["point_format"], pf);
    EXPECT_EQ(h.details["record_length"], kBase[pf] + kExtraBytes);
    EXPECT_EQ(h.rgbBits, rgb(pf) ? 16 : 0);
    ASSERT_TRUE(h.scale && h.offset);
    EXPECT_EQ(*h.scale, (Vec3d{0.01, 0.01, 0.01}));
    EXPECT_EQ(*h.offset, (Vec3d{1000, 2000, -10}));
    const auto expected = expectedLayout(pf);
    ASSERT_EQ(h.layout.size(), expected.size());
    for (size_t a = 0; a < expected.size(); ++a) {
      EXPECT_EQ(h.layout[a].name, expected[a].name);
      EXPECT_EQ(h.layout[a].type, expected[a].type) << expected[a].name;
      EXPECT_EQ(h.layout[a].components, expected[a].components) << expected[a].name;
    }
    EXPECT_NE(h.layout[h.layout.find("height")].description.find("scale=0.01"), std::string::npos);
    EXPECT_TRUE(r->warnings().empty()) << r->warnings().front();

    expectPointsMatch(pf, readLasPoints(*r), kPoints);
    // Rewind starts again from the first point.
    r->rewind();
    PointBatch b;
    ASSERT_TRUE(r->read(b, 1));
    EXPECT_EQ(b.xyz[0], makePoint(pf, 0).X * 0.01 + 1000);
    EXPECT_EQ(r->bytesTotal(), makeFile(pf, kPoints).bytes().size());
  }
}

TEST(LasReader, ZeroPointsIsAnEmptyFile) {
  LasFile f;
  f.pf = 3;
  auto r = openBytes(f.bytes());
  EXPECT_EQ(r->header().declaredPoints, uint64_t(0));
  EXPECT_TRUE(r->header().layout.has("rgb"));
  PointBatch b;
  EXPECT_FALSE(r->read(b, 100));
  EXPECT_EQ(b.size(), 0u);
  EXPECT_TRUE(r->warnings().empty());
}

TEST(LasReader, EmptyFileIsAnError) {
  TempDir dir;
  const std::string path = dir.file("empty.las");
  test::writeFile(path, "");
  try {
    openReader(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.reason().find("empty"), std::string::npos) << e.what();
  }
  EXPECT_THROW(openBytes(""), Error);
}

TEST(LasReader, TruncatedFileIsAnErrorNamingTheFile) {
  LasFile f = makeFile(2, 100);
  std::string bytes = f.bytes();
  bytes.resize(bytes.size() - 50);  // one record and 13 bytes of another
  TempDir dir;
  const std::string path = dir.file("truncated.las");
  test::writeFile(path, bytes);
  const size_t pointStart = 227 + 54 + 2 * 192;
  const size_t recordLength = kBase[2] + kExtraBytes;
  const size_t complete = (bytes.size() - pointStart) / recordLength;
  ASSERT_EQ(complete, 98u);
  try {
    openReader(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_EQ(e.position(), Error::atByte(pointStart + complete * recordLength));
    EXPECT_NE(what.find("declares 100 points"), std::string::npos) << what;
    EXPECT_NE(what.find("only 98 complete records"), std::string::npos) << what;
  }
}

TEST(LasReader, LenientModeKeepsCompleteRecordsAndWarns) {
  std::string bytes = makeFile(7, 100).bytes();
  bytes.resize(bytes.size() - 50);
  ReadOptions o;
  o.lenient = true;
  auto r = openBytes(bytes, o);
  EXPECT_EQ(r->header().declaredPoints, uint64_t(100));
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("only 98 complete records"), std::string::npos)
      << r->warnings()[0];
  expectPointsMatch(7, readLasPoints(*r), 98);
}

TEST(LasReader, HeaderClaimingFewerPointsWarns) {
  LasFile f = makeFile(1, 100);
  f.declared = 90;
  auto r = openBytes(f.bytes());
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("10 more records"), std::string::npos) << r->warnings()[0];
  expectPointsMatch(1, readLasPoints(*r), 90);
}

TEST(LasReader, EvlrsAfterThePointsAreNotTrailingBytes) {
  LasFile f = makeFile(6, 10);
  const std::string wkt = "PROJCS[\"test\"]";
  f.evlrs.push_back(evlr("LASF_Projection", 2112, wkt + '\0'));
  auto r = openBytes(f.bytes());
  EXPECT_TRUE(r->warnings().empty()) << r->warnings().front();
  EXPECT_EQ(r->header().crs["wkt"], wkt);
  expectPointsMatch(6, readLasPoints(*r), 10);

  // Bytes between the points and the EVLRs are reported.
  f.trailing = "junk";
  r = openBytes(f.bytes());
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("4 bytes after the 10 declared points"), std::string::npos);
}

TEST(LasReader, CoordinateSystemVlrs) {
  LasFile f = makeFile(3, 3);
  const std::string wkt = "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\"]]";
  std::string keys;
  for (uint16_t k : {1, 1, 0, 1, 3072, 0, 1, 32610}) put(keys, keys.size(), k);
  std::string doubles;
  put(doubles, 0, 6378137.0);
  f.vlrs.push_back(vlr("LASF_Projection", 34735, keys));
  f.vlrs.push_back(vlr("LASF_Projection", 34736, doubles));
  f.vlrs.push_back(vlr("LASF_Projection", 34737, std::string("WGS 84|\0", 8)));
  f.vlrs.push_back(vlr("LASF_Projection", 2112, wkt + '\0'));
  auto r = openBytes(f.bytes());
  const nlohmann::json& crs = r->header().crs;
  EXPECT_EQ(crs["wkt"], wkt);
  EXPECT_EQ(crs["geotiff"]["keys"], (nlohmann::json{1, 1, 0, 1, 3072, 0, 1, 32610}));
  EXPECT_EQ(crs["geotiff"]["doubles"], (nlohmann::json{6378137.0}));
  EXPECT_EQ(crs["geotiff"]["ascii"], "WGS 84|");
  EXPECT_EQ(r->header().details["vlrs"].size(), 5u);

  // A file without them has no CRS.
  EXPECT_TRUE(openBytes(makeFile(3, 3).bytes())->header().crs.is_null());
}

TEST(LasReader, ExtraBytesDescriptors) {
  // Type 0 (undocumented, `options` bytes), a name that repeats a standard field, a 3-array.
  LasFile f;
  f.pf = 0;
  f.vlrs.push_back(vlr("LASF_Spec", 4,
                       extraBytesDescriptor("blob", 0, 5) +
                           extraBytesDescriptor("intensity", 3, 0) +
                           extraBytesDescriptor("vec", 29, 0) + extraBytesDescriptor("", 1, 0)));
  std::string rec = encodeRecord(0, makePoint(0, 1)).substr(0, 20);
  rec += std::string("abcde");
  put(rec, rec.size(), uint16_t(777));
  put(rec, rec.size(), std::array<float, 3>{1.5f, -2.f, 3.25f});
  rec += '\x09';
  rec += "zz";  // not described
  f.records = {rec};
  auto r = openBytes(f.bytes());
  const PointLayout& l = r->header().layout;
  ASSERT_GE(l.size(), 5u);
  const size_t n = l.size();
  EXPECT_EQ(l[n - 5], (Attribute{"blob", ScalarType::U8, 5, ""}));
  EXPECT_EQ(l[n - 4], (Attribute{"intensity_2", ScalarType::U16, 1, ""}));
  EXPECT_EQ(l[n - 3], (Attribute{"vec", ScalarType::F32, 3, ""}));
  EXPECT_EQ(l[n - 2], (Attribute{"extra_3", ScalarType::U8, 1, ""}));
  EXPECT_EQ(l[n - 1], (Attribute{"extra_bytes", ScalarType::U8, 2, ""}));
  AllPoints all = readLasPoints(*r);
  ASSERT_EQ(all.size(), 1u);
  EXPECT_EQ(all.get("blob", 0, 4), 'e');
  EXPECT_EQ(all.get("intensity", 0), makePoint(0, 1).intensity);
  EXPECT_EQ(all.get("intensity_2", 0), 777);
  EXPECT_EQ(all.get("vec", 0, 2), 3.25);
  EXPECT_EQ(all.get("extra_3", 0), 9);
  EXPECT_EQ(all.get("extra_bytes", 0, 1), 'z');

  // Descriptors that describe more bytes than the records have: kept as undocumented bytes.
  f.records = {encodeRecord(0, makePoint(0, 1)).substr(0, 24)};
  r = openBytes(f.bytes());
  EXPECT_EQ(r->header().layout[r->header().layout.size() - 1],
            (Attribute{"extra_bytes", ScalarType::U8, 4, ""}));
  EXPECT_FALSE(r->warnings().empty());
}

TEST(LasReader, MalformedHeadersAreErrors) {
  LasFile base = makeFile(0, 3);
  base.vlrs.insert(base.vlrs.begin(), vlr("someone", 1, "0123456789"));
  const std::string good = base.bytes();
  ASSERT_NO_THROW(openBytes(good));
  struct Case {
    const char* what;
    std::function<void(std::string&)> mutate;
    const char* reason;
    const char* position;
  };
  const Case cases[] = {
      {"signature", [](std::string& s) { s[0] = 'X'; }, "no 'LASF' signature", "byte 0"},
      {"short", [](std::string& s) { s.resize(100); }, "ends inside the LAS header", "byte 100"},
      {"version", [](std::string& s) { s[24] = 2; }, "unsupported LAS version 2.0", "byte 24"},
      {"header size", [](std::string& s) { put(s, 94, uint16_t(200)); }, "header size 200",
       "byte 94"},
      {"point offset", [](std::string& s) { put(s, 96, uint32_t(1 << 30)); },
       "beyond the end of the file", "byte 96"},
      {"point offset in header", [](std::string& s) { put(s, 96, uint32_t(100)); },
       "inside the header", "byte 96"},
      {"vlr length", [](std::string& s) { put(s, 227 + 20, uint16_t(60000)); },
       "variable length record 1 of 2 (60000 bytes) runs past the end of the file", "byte 227"},
      {"record length", [](std::string& s) { put(s, 105, uint16_t(19)); },
       "smaller than the 20 bytes point format 0 needs", "byte 105"},
      {"point format", [](std::string& s) { s[104] = 11; }, "unknown point data record format 11",
       "byte 104"},
      {"laz", [](std::string& s) { s[104] = char(0x80); }, "there is no LASzip record", "byte 104"},
      {"laz bit 6", [](std::string& s) { s[104] = char(0x40); }, "there is no LASzip record",
       "byte 104"},
  };
  // VLRs that would run past the end of a file without points.
  LasFile empty;
  empty.vlrs.push_back(vlr("someone", 1, "0123456789"));
  std::string noPoints = empty.bytes();
  put(noPoints, 100, uint32_t(4000000000u));
  try {
    openBytes(noPoints, {}, "bad.las");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(
        e.reason().find("variable length record 2 of 4000000000 runs past the end of the file"),
        std::string::npos)
        << e.what();
    EXPECT_EQ(e.position(), Error::atByte(227 + 64));
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    std::string bytes = good;
    c.mutate(bytes);
    try {
      openBytes(bytes, {}, "bad.las");
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.file(), "bad.las");
      EXPECT_NE(e.reason().find(c.reason), std::string::npos) << e.what();
      if (*c.position) {
        EXPECT_EQ(e.position(), c.position) << e.what();
      }
    }
  }
}

// A cheap, deterministic stand-in for the fuzzer in every test run: corrupt header, VLR and
// point bytes and check that the reader either reads or throws nestlight::Error.
TEST(LasReader, SurvivesCorruptedBytes) {
  LasFile f = makeFile(10, 5);
  f.minor = 4;
  f.vlrs.push_back(vlr("LASF_Projection", 2112, "WKT\xff\x01"));
  f.evlrs.push_back(evlr("LASF_Projection", 34735, "\x01\x00\x01\x00"));
  const std::string good = f.bytes();
  std::mt19937 rng(7);
  for (int iter = 0; iter < 3000; ++iter) {
    std::string s = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      // Mostly the header and VLRs, where the structure is.
      const size_t at = rng() % 2 ? rng() % 420 : rng() % s.size();
      s[at % s.size()] = static_cast<char>(rng());
    }
    if (rng() % 8 == 0) s.resize(rng() % s.size());
    try {
      ReadOptions o;
      o.lenient = rng() % 2;
      auto r = openBytes(s, o);
      PointBatch b;
      size_t n = 0;
      while (r->read(b, 3)) n += b.size();
      EXPECT_LE(n, r->header().declaredPoints.value_or(0));
      (void)r->header().crs.dump();
      (void)r->header().details.dump();
    } catch (const Error&) {
    }
  }
}

TEST(LasReader, OpenReaderOpensLazByExtension) {
  // .laz goes to the LAS reader, which reads the file (here: names the missing one).
  try {
    openReader("/nonexistent/scan.laz");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/nonexistent/scan.laz");
    EXPECT_EQ(std::string(e.what()).find("not supported"), std::string::npos) << e.what();
  }
}

// ---- Writer ---------------------------------------------------------------------------------

TEST(LasWriter, RoundTripsEveryPointFormat) {
  // Formats with wave packets are written without them (their fields go to extra bytes).
  const int written[11] = {0, 1, 2, 3, 1, 3, 6, 7, 8, 6, 8};
  constexpr int kPoints = 40;
  TempDir dir;
  for (int pf = 0; pf <= 10; ++pf) {
    SCOPED_TRACE("point format " + std::to_string(pf));
    auto source = openBytes(makeFile(pf, kPoints).bytes());
    const std::string path = dir.file("pf" + std::to_string(pf) + ".las");
    copyTo(*source, path);
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
    source->rewind();
    const AllPoints a = readLasPoints(*source);

    auto back = openReader(path);
    EXPECT_TRUE(back->warnings().empty()) << back->warnings().front();
    EXPECT_EQ(back->header().details["point_format"], written[pf]);
    EXPECT_EQ(back->header().details["version"], written[pf] >= 6 ? "1.4" : "1.2");
    EXPECT_EQ(back->header().declaredPoints, uint64_t(kPoints));
    EXPECT_EQ(*back->header().scale, *source->header().scale);
    EXPECT_EQ(*back->header().offset, *source->header().offset);
    const AllPoints b = readLasPoints(*back);
    ASSERT_EQ(b.size(), a.size());
    EXPECT_EQ(b.xyz, a.xyz);
    // Every attribute comes back under its name, with its type and bytes.
    for (size_t i = 0; i < a.layout.size(); ++i) {
      const Attribute& attr = a.layout[i];
      const int j = b.layout.find(attr.name);
      ASSERT_GE(j, 0) << attr.name;
      EXPECT_EQ(b.layout[j], attr);
      for (size_t p = 0; p < a.size(); ++p)
        ASSERT_EQ(
            0, std::memcmp(&a.attrs[p * a.layout.stride() + a.layout.offset(i)],
                           &b.attrs[p * b.layout.stride() + b.layout.offset(j)], attr.byteSize()))
            << attr.name << " of point " << p;
    }
    // The header bounds are those of the points.
    Box3d box;
    for (size_t p = 0; p < b.size(); ++p)
      box.extend(b.xyz[3 * p], b.xyz[3 * p + 1], b.xyz[3 * p + 2]);
    EXPECT_EQ(*back->header().declaredBounds, box);
  }
}

SourceHeader simpleHeader(std::vector<Attribute> attributes) {
  SourceHeader h;
  h.format = "test";
  h.layout = PointLayout(std::move(attributes));
  return h;
}

TEST(LasWriter, NationalGridCoordinatesRoundTripExactly) {
  TempDir dir;
  // Millimetre positions around (500 km, 5000 km), as a surveyor's file holds them: 5e9 mm do
  // not fit 32 bits, so the file needs an offset, given or chosen by the writer.
  std::mt19937_64 rng(3);
  std::vector<std::array<int64_t, 3>> mm(1000);
  for (auto& p : mm)
    p = {500000000 + static_cast<int64_t>(rng() % 2000000),
         5000000000 + static_cast<int64_t>(rng() % 2000000), static_cast<int64_t>(rng() % 300000)};
  for (bool given : {true, false}) {
    SCOPED_TRACE(given ? "offset given" : "offset chosen by the writer");
    SourceHeader h = simpleHeader({});
    h.scale = Vec3d{0.001, 0.001, 0.001};
    // The writer takes the floor of the first point.
    const Vec3d offset = given ? Vec3d{500000, 5000000, 0}
                               : Vec3d{std::floor(mm[0][0] / 1000.0), std::floor(mm[0][1] / 1000.0),
                                       std::floor(mm[0][2] / 1000.0)};
    if (given) h.offset = offset;
    PointBatch in;
    for (const auto& p : mm)
      for (int a = 0; a < 3; ++a)
        in.xyz.push_back(
            static_cast<double>(p[a] - static_cast<int64_t>(offset[a]) * 1000) * 0.001 + offset[a]);
    const std::string path = dir.file(given ? "grid_offset.las" : "grid.las");
    auto w = createLasWriter(path, h);
    w->write(in);
    w->close();
    auto r = openReader(path);
    EXPECT_EQ(*r->header().scale, *h.scale);
    EXPECT_EQ(*r->header().offset, offset);
    EXPECT_EQ(r->header().details["point_format"], 0);
    const AllPoints out = readLasPoints(*r, 300);
    EXPECT_EQ(out.xyz, in.xyz);
    // And within a nanometre of the millimetre values themselves.
    for (size_t i = 0; i < mm.size(); ++i)
      for (int a = 0; a < 3; ++a) ASSERT_NEAR(out.xyz[3 * i + a], mm[i][a] * 0.001, 1e-9);
  }
}

TEST(LasWriter, DefaultQuantisationIsMillimetresFromTheFirstPoint) {
  TempDir dir;
  const std::string path = dir.file("default.las");
  PointBatch in;
  in.xyz = {500000.1234567, 5000000.9876543, 12.3456789, 500001.5, 4999999.25, -3.0005};
  auto w = createLasWriter(path, simpleHeader({}));
  w->write(in);
  w->close();
  auto r = openReader(path);
  EXPECT_EQ(*r->header().scale, (Vec3d{0.001, 0.001, 0.001}));
  EXPECT_EQ(*r->header().offset, (Vec3d{500000, 5000000, 12}));
  const AllPoints out = readLasPoints(*r);
  ASSERT_EQ(out.size(), 2u);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(out.xyz[k], in.xyz[k], 0.0005 + 1e-9);
  EXPECT_EQ(out.xyz[0], 123 * 0.001 + 500000);
  // Points without return numbers are single returns.
  EXPECT_EQ(out.get("return_number", 1), 1);
  EXPECT_EQ(out.get("number_of_returns", 1), 1);
}

TEST(LasWriter, ZeroPoints) {
  TempDir dir;
  const std::string path = dir.file("none.las");
  auto w = createLasWriter(path, simpleHeader({{"rgb", ScalarType::U16, 3, ""}}));
  w->close();
  auto r = openReader(path);
  EXPECT_EQ(r->header().declaredPoints, uint64_t(0));
  EXPECT_EQ(r->header().details["point_format"], 2);
  PointBatch b;
  EXPECT_FALSE(r->read(b, 10));
}

TEST(LasWriter, OtherAttributesGoToExtraBytes) {
  TempDir dir;
  const std::string path = dir.file("extra.las");
  const std::string longName = "a_very_long_attribute_name_that_exceeds_32_characters";
  SourceHeader h = simpleHeader({{"normal", ScalarType::F32, 3, "unit normal"},
                                 {"rgb", ScalarType::U16, 3, ""},
                                 {longName, ScalarType::F64, 1, ""},
                                 {"quad", ScalarType::I32, 4, ""},
                                 {"blob", ScalarType::U8, 7, ""},
                                 {"intensity", ScalarType::F32, 1, "not a LAS intensity"}});
  PointBatch in;
  in.xyz = {1, 2, 3, 4, 5, 6};
  in.attrs.resize(2 * h.layout.stride());
  for (size_t k = 0; k < in.attrs.size(); ++k) in.attrs[k] = static_cast<uint8_t>(k * 37 + 11);
  auto w = createLasWriter(path, h);
  w->write(in);
  w->close();
  auto r = openReader(path);
  EXPECT_EQ(r->header().details["point_format"], 2);
  EXPECT_TRUE(r->warnings().empty());
  const AllPoints out = readLasPoints(*r);
  ASSERT_EQ(out.size(), 2u);
  auto expectSame = [&](const std::string& inName, const std::string& outName) {
    const int i = h.layout.find(inName), o = out.layout.find(outName);
    ASSERT_GE(o, 0) << outName;
    EXPECT_EQ(out.layout[o].type, h.layout[i].type);
    for (size_t p = 0; p < 2; ++p)
      EXPECT_EQ(0, std::memcmp(&in.attrs[p * h.layout.stride() + h.layout.offset(i)],
                               &out.attrs[p * out.layout.stride() + out.layout.offset(o)],
                               out.layout[o].byteSize()))
          << outName;
  };
  expectSame("normal", "normal");
  EXPECT_EQ(out.layout[out.layout.find("normal")].components, 3u);
  expectSame("rgb", "rgb");
  expectSame(longName, longName.substr(0, 32));
  expectSame("blob", "blob");
  // A float "intensity" does not fit the record's integer field: it stays float, beside it.
  expectSame("intensity", "intensity_2");
  // Arrays longer than three are one descriptor per component.
  const int q1 = out.layout.find("quad[1]");
  ASSERT_GE(q1, 0);
  EXPECT_EQ(out.layout[q1], (Attribute{"quad[1]", ScalarType::I32, 1, ""}));
  EXPECT_EQ(0, std::memcmp(&in.attrs[h.layout.offset(h.layout.find("quad")) + 4],
                           &out.attrs[out.layout.offset(q1)], 4));
}

// A layout that fits format 1 until points with 9 returns arrive in the second batch: the file
// is upgraded to format 6, LAS 1.4, and every point reads back.
void checkUpgrade(bool laz, int first, int second) {
  TempDir dir;
  const std::string path = dir.file(laz ? "upgrade.laz" : "upgrade.las");
  SourceHeader h = simpleHeader({{"return_number", ScalarType::U8, 1, ""},
                                 {"number_of_returns", ScalarType::U8, 1, ""},
                                 {"classification", ScalarType::U8, 1, ""},
                                 {"scan_angle_rank", ScalarType::I8, 1, ""},
                                 {"gps_time", ScalarType::F64, 1, ""}});
  h.scale = Vec3d{0.01, 0.01, 0.01};
  h.crs["wkt"] = "PROJCS[\"x\"]";
  auto w = laz ? createLazWriter(path, h) : createLasWriter(path, h);
  auto batch = [&](int from, int n, int returns) {
    PointBatch b;
    for (int i = from; i < from + n; ++i) {
      b.xyz.insert(b.xyz.end(), {i * 1.0, i * 2.0, i * 0.5});
      b.attrs.push_back(static_cast<uint8_t>(1 + i % returns));
      b.attrs.push_back(static_cast<uint8_t>(returns));
      b.attrs.push_back(static_cast<uint8_t>(i % 32));
      b.attrs.push_back(static_cast<uint8_t>(-i));
      const double t = 1000 + i * 0.001;
      b.attrs.resize(b.attrs.size() + 8);
      std::memcpy(&b.attrs[b.attrs.size() - 8], &t, 8);
    }
    return b;
  };
  w->write(batch(0, first, 3));
  w->write(batch(first, second, 9));
  w->close();
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp2"));
  auto r = openReader(path);
  EXPECT_EQ(r->header().details["point_format"], 6);
  EXPECT_EQ(r->header().details["version"], "1.4");
  if (laz) {
    EXPECT_EQ(r->header().details["laszip"]["compressor"], "layered chunked");
  }
  EXPECT_EQ(r->header().details["global_encoding"].get<int>() & 16, 16);  // WKT
  EXPECT_EQ(r->header().crs["wkt"], "PROJCS[\"x\"]");
  const AllPoints out = readLasPoints(*r);
  const int total = first + second;
  ASSERT_EQ(out.size(), size_t(total));
  int wrong = 0;
  for (int i = 0; i < total && wrong < 5; ++i) {
    const int returns = i < first ? 3 : 9;
    const bool ok = out.get("return_number", i) == 1 + i % returns &&
                    out.get("number_of_returns", i) == returns &&
                    out.get("classification", i) == i % 32 &&
                    out.get("scan_angle_rank", i) == static_cast<int8_t>(-i) &&
                    out.get("gps_time", i) == 1000 + i * 0.001 &&
                    out.xyz[3 * i + 1] == std::nearbyint(i * 200.0) * 0.01;
    if (!ok) ADD_FAILURE() << "point " << i << " differs", ++wrong;
  }
  // Counts by return in the header.
  uint64_t want[9] = {};
  for (int i = 0; i < total; ++i) ++want[i % (i < first ? 3 : 9)];
  const auto& byReturn = r->header().details["points_by_return"];
  EXPECT_EQ(byReturn[0], want[0]);
  EXPECT_EQ(byReturn[8], want[8]);
}

TEST(LasWriter, ValuesOnlyFormat6HoldsUpgradeTheFile) {
  checkUpgrade(false, 100, 100);
}

// LAZ is compressed as points arrive, so the upgrade decodes the chunks already written (more
// than one group of them here, and a partial chunk still held) and compresses them again.
TEST(LazWriter, ValuesOnlyFormat6HoldsUpgradeTheCompressedFile) {
  checkUpgrade(true, 100, 100);
  checkUpgrade(true, 16 * 50000 + 30000, 70000);
}

TEST(LasWriter, UnrepresentablePointsAreErrorsAndLeaveNoFile) {
  TempDir dir;
  const std::string path = dir.file("nan.las");
  {
    auto w = createLasWriter(path, simpleHeader({}));
    PointBatch b;
    b.xyz = {1, 2, 3, 4, NAN, 6};
    try {
      w->write(b);
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.position(), "point 1");
    }
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));

  // 3000 km from the offset does not fit 32-bit millimetres.
  auto w = createLasWriter(path, simpleHeader({}));
  PointBatch b;
  b.xyz = {0, 0, 0, 3.0e6, 0, 0};
  EXPECT_THROW(w->write(b), Error);

  // 16 returns fit no LAS point format: an error, not a value cut to four bits.
  w = createLasWriter(path, simpleHeader({{"return_number", ScalarType::U8, 1, ""}}));
  b.xyz = {0, 0, 0};
  b.attrs = {16};
  try {
    w->write(b);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(e.reason().find("return_number 16 does not fit"), std::string::npos) << e.what();
  }
}

TEST(LasWriter, CoordinateSystemIsWritten) {
  TempDir dir;
  LasFile f = makeFile(3, 2);
  std::string keys;
  for (uint16_t k : {1, 1, 0, 1, 3072, 0, 1, 32610}) put(keys, keys.size(), k);
  f.vlrs.push_back(vlr("LASF_Projection", 34735, keys));
  f.vlrs.push_back(vlr("LASF_Projection", 2112, std::string("PROJCS[\"UTM 10N\"]") + '\0'));
  auto source = openBytes(f.bytes());
  const std::string path = dir.file("crs.las");
  copyTo(*source, path);
  auto r = openReader(path);
  EXPECT_EQ(r->header().crs, source->header().crs);
  EXPECT_EQ(r->header().details["global_encoding"], 0);  // LAS 1.2 has no WKT bit
}

// ---- Real scans -----------------------------------------------------------------------------

struct Summary {
  AllPoints points;
  std::map<int, size_t> classes;
  uint64_t intensitySum = 0;
  std::array<uint64_t, 3> rgbSum{};
};
Summary summarise(PointReader& r) {
  Summary s;
  s.points = readLasPoints(r, 50000);
  for (size_t i = 0; i < s.points.size(); ++i) {
    ++s.classes[static_cast<int>(s.points.get("classification", i))];
    s.intensitySum += static_cast<uint64_t>(s.points.get("intensity", i));
    for (int c = 0; c < 3; ++c) s.rgbSum[c] += static_cast<uint64_t>(s.points.get("rgb", i, c));
  }
  return s;
}

void expectBoundsMatchHeader(const PointReader& r, const AllPoints& p) {
  Box3d box;
  for (size_t i = 0; i < p.size(); ++i)
    box.extend(p.xyz[3 * i], p.xyz[3 * i + 1], p.xyz[3 * i + 2]);
  const Box3d& d = *r.header().declaredBounds;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(box.min[a], d.min[a], 1e-6);
    EXPECT_NEAR(box.max[a], d.max[a], 1e-6);
  }
}

TEST(LasRealData, AutzenPointFormat3) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  auto r = openReader((test::sharedData() / "scans/autzen_trim.las").string());
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.declaredPoints, uint64_t(110000));
  EXPECT_EQ(h.details["point_format"], 3);
  EXPECT_EQ(h.details["version"], "1.2");
  EXPECT_EQ(h.details["generating_software"], "PDAL 1.0.0 (9e8465)");
  EXPECT_EQ(h.rgbBits, 16);
  ASSERT_FALSE(h.crs.is_null());
  EXPECT_EQ(
      h.crs["wkt"].get<std::string>().rfind("PROJCS[\"NAD_1983_HARN_Lambert_Conformal_Conic\"", 0),
      0u);
  // GeoKeyDirectory: version 1.1.0 with 21 keys, carried verbatim (92 values with padding).
  EXPECT_EQ(h.crs["geotiff"]["keys"].size(), 92u);
  EXPECT_EQ(h.crs["geotiff"]["keys"][3], 21);
  EXPECT_TRUE(r->warnings().empty());
  const Summary s = summarise(*r);
  ASSERT_EQ(s.points.size(), 110000u);
  EXPECT_EQ(s.points.xyz[0], 63717798 * 0.01);
  EXPECT_EQ(s.points.xyz[1], 84939395 * 0.01);
  EXPECT_EQ(s.points.xyz[2], 41119 * 0.01);
  EXPECT_EQ(s.points.get("gps_time", 0), 245379.39843682514);
  EXPECT_EQ(s.points.get("gps_time", 109999), 245385.91112104454);
  EXPECT_EQ(s.classes, (std::map<int, size_t>{{1, 83893}, {2, 26107}}));
  EXPECT_EQ(s.intensitySum, 11220547u);
  EXPECT_EQ(s.rgbSum, (std::array<uint64_t, 3>{12255922, 13168529, 10938029}));
  expectBoundsMatchHeader(*r, s.points);
}

TEST(LasRealData, AutzenLas14Format7HasTheSamePoints) {
  NL_REQUIRE_SHARED("scans/autzen_trim.las");
  NL_REQUIRE_SHARED("scans/autzen_trim_las14_pf7.las");
  auto r3 = openReader((test::sharedData() / "scans/autzen_trim.las").string());
  auto r7 = openReader((test::sharedData() / "scans/autzen_trim_las14_pf7.las").string());
  EXPECT_EQ(r7->header().details["point_format"], 7);
  EXPECT_EQ(r7->header().details["version"], "1.4");
  EXPECT_EQ(r7->header().declaredPoints, uint64_t(110000));
  EXPECT_TRUE(r7->header().crs["wkt"].is_string());
  EXPECT_TRUE(r7->warnings().empty());
  const Summary s3 = summarise(*r3), s7 = summarise(*r7);
  ASSERT_EQ(s7.points.size(), 110000u);
  EXPECT_EQ(s7.points.xyz, s3.points.xyz);
  EXPECT_EQ(s7.classes, s3.classes);
  EXPECT_EQ(s7.intensitySum, s3.intensitySum);
  EXPECT_EQ(s7.rgbSum, s3.rgbSum);
  for (size_t i = 0; i < 110000; i += 997) {
    EXPECT_EQ(s7.points.get("gps_time", i), s3.points.get("gps_time", i));
    EXPECT_EQ(s7.points.get("return_number", i), s3.points.get("return_number", i));
  }
}

TEST(LasRealData, LionPointFormat2) {
  NL_REQUIRE_SHARED("scans/lion_takanawa.las");
  auto r = openReader((test::sharedData() / "scans/lion_takanawa.las").string());
  EXPECT_EQ(r->header().declaredPoints, uint64_t(341989));
  EXPECT_EQ(r->header().details["point_format"], 2);
  EXPECT_EQ(r->header().rgbBits, 16);
  EXPECT_TRUE(r->header().crs.is_null());
  const Summary s = summarise(*r);
  ASSERT_EQ(s.points.size(), 341989u);
  EXPECT_EQ(s.points.xyz[0], -2544 * 0.001);
  EXPECT_EQ(s.points.xyz[3 * 341988 + 2], -548 * 0.001);
  EXPECT_EQ(s.points.get("rgb", 0, 0), 49408);
  EXPECT_EQ(s.points.get("rgb", 0, 2), 52736);
  EXPECT_EQ(s.intensitySum, 11553659104u);
  EXPECT_EQ(s.rgbSum, (std::array<uint64_t, 3>{11497181696, 11646132480, 11200297216}));
  expectBoundsMatchHeader(*r, s.points);
  EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());

  // Written back, the scan reads the same.
  TempDir dir;
  const std::string path = dir.file("lion.las");
  r->rewind();
  copyTo(*r, path, 65536);
  auto back = openReader(path);
  EXPECT_EQ(back->header().details["point_format"], 2);
  const Summary b = summarise(*back);
  EXPECT_EQ(b.points.xyz, s.points.xyz);
  EXPECT_EQ(b.points.attrs, s.points.attrs);
}

}  // namespace
}  // namespace nestlight
