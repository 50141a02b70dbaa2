// PLY reader and writer: ascii and binary files of both byte orders written byte by byte here and
// checked value by value, faces before and after the vertices, headers that lie, truncated and
// malformed files, round trips through the writer, and two real files from ../shared/data.
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight {
namespace {

using test::anyContains;
using test::attrAt;
using test::errorOf;
using test::Points;
using test::readAll;
using test::TempDir;

// Appends `v` in the given byte order.
template <typename T>
void put(std::string& s, T v, bool bigEndian = false) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (bigEndian == (std::endian::native == std::endian::little)) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

std::shared_ptr<ByteSource> source(const std::string& bytes, std::string name = "test.ply") {
  return memorySource(std::move(name), std::vector<uint8_t>(bytes.begin(), bytes.end()));
}

TEST(PlyReader, AsciiValuesColourAndUnknownProperties) {
  const std::string ply =
      "ply\n"
      "format ascii 1.0\n"
      "comment made by hand\n"
      "element vertex 3\n"
      "property float x\n"
      "property float y\n"
      "property double z\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "property float confidence\n"
      "property int ring\n"
      "end_header\n"
      "1.5 -2.25 1e3 255 0 128 0.5 -7\n"
      "\n"
      "0 0 -0.125 1 2 3 1 2147483647\r\n"
      "+4 5.5 6 10 20 30 nan 0\n";
  auto r = openPly(source(ply));
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.format, "ply");
  EXPECT_EQ(h.declaredPoints, 3u);
  EXPECT_EQ(h.rgbBits, 8);
  EXPECT_TRUE(h.crs.is_null());
  EXPECT_EQ(h.details["encoding"], "ascii");
  EXPECT_EQ(h.details["comments"][0], "made by hand");
  ASSERT_EQ(h.layout.size(), 3u);
  EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"confidence", ScalarType::F32, 1, ""}));
  EXPECT_EQ(h.layout[2], (Attribute{"ring", ScalarType::I32, 1, ""}));

  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p.xyz, (std::vector<double>{1.5, -2.25, 1000, 0, 0, -0.125, 4, 5.5, 6}));
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 0), 65535);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 1), 0);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 2), 128 * 257);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 2), 3 * 257);
  EXPECT_EQ(attrAt<float>(p, *r, 0, "confidence"), 0.5f);
  EXPECT_TRUE(std::isnan(attrAt<float>(p, *r, 2, "confidence")));
  EXPECT_EQ(attrAt<int32_t>(p, *r, 0, "ring"), -7);
  EXPECT_EQ(attrAt<int32_t>(p, *r, 1, "ring"), 2147483647);
  EXPECT_TRUE(r->warnings().empty());
  EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());
}

std::string binaryFloatRgb(uint64_t declared, int records, bool withTail = false) {
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex " +
                  std::to_string(declared) +
                  "\nproperty float x\nproperty float y\nproperty float z\n"
                  "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  for (int i = 0; i < records; ++i) {
    put(s, float(i) + 0.5f);
    put(s, float(-i));
    put(s, float(i) * 1024.0f);
    put(s, uint8_t(i));
    put(s, uint8_t(2 * i));
    put(s, uint8_t(255 - i));
  }
  if (withTail) s += "xyz";  // half a record
  return s;
}

TEST(PlyReader, BinaryLittleEndian) {
  auto r = openPly(source(binaryFloatRgb(100, 100)));
  EXPECT_EQ(r->header().details["encoding"], "binary_little_endian");
  EXPECT_EQ(r->header().rgbBits, 8);
  Points p = readAll(*r, 7);  // batches that do not divide the count
  ASSERT_EQ(p.size(), 100u);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(p.xyz[3 * i], i + 0.5);
    EXPECT_EQ(p.xyz[3 * i + 1], -i);
    EXPECT_EQ(p.xyz[3 * i + 2], i * 1024.0);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 0), i * 257);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 1), 2 * i * 257);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 2), (255 - i) * 257);
  }
  // Rewind gives the same points again.
  r->rewind();
  Points q = readAll(*r, 1000);
  EXPECT_EQ(q.xyz, p.xyz);
  EXPECT_EQ(q.attrs, p.attrs);
}

TEST(PlyReader, BigEndianMixedTypesExact) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\n"
      "property double x\nproperty float y\nproperty int z\n"
      "property ushort red\nproperty ushort green\nproperty ushort blue\n"
      "property short temperature\nproperty uint id\nproperty double gps_time\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property ushort intensity\n"
      "end_header\n";
  const double xs[2] = {512345.678901234, -0.1};
  const float ys[2] = {5123456.5f, 3.25f};
  const int32_t zs[2] = {-123456, 7};
  for (int i = 0; i < 2; ++i) {
    put(s, xs[i], true);
    put(s, ys[i], true);
    put(s, zs[i], true);
    put(s, uint16_t(0x1234 + i), true);
    put(s, uint16_t(0xFFFF), true);
    put(s, uint16_t(0), true);
    put(s, int16_t(-300 - i), true);
    put(s, uint32_t(0xDEADBEEF - i), true);
    put(s, 1.0e9 + 0.25 * i, true);
    put(s, 0.0f, true);
    put(s, 0.6f, true);
    put(s, -0.8f, true);
    put(s, uint16_t(40000 + i), true);
  }
  auto r = openPly(source(s));
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.details["encoding"], "binary_big_endian");
  EXPECT_EQ(h.rgbBits, 16);
  ASSERT_EQ(h.layout.size(), 6u);
  EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"temperature", ScalarType::I16, 1, ""}));
  EXPECT_EQ(h.layout[2], (Attribute{"id", ScalarType::U32, 1, ""}));
  EXPECT_EQ(h.layout[3], (Attribute{"gps_time", ScalarType::F64, 1, ""}));
  EXPECT_EQ(h.layout[4], (Attribute{"normal", ScalarType::F32, 3, ""}));
  EXPECT_EQ(h.layout[5], (Attribute{"intensity", ScalarType::U16, 1, ""}));
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(p.xyz[3 * i], xs[i]);
    EXPECT_EQ(p.xyz[3 * i + 1], double(ys[i]));
    EXPECT_EQ(p.xyz[3 * i + 2], zs[i]);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 0), 0x1234 + i);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 1), 0xFFFF);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "rgb", 2), 0);
    EXPECT_EQ(attrAt<int16_t>(p, *r, i, "temperature"), -300 - i);
    EXPECT_EQ(attrAt<uint32_t>(p, *r, i, "id"), 0xDEADBEEFu - i);
    EXPECT_EQ(attrAt<double>(p, *r, i, "gps_time"), 1.0e9 + 0.25 * i);
    EXPECT_EQ(attrAt<float>(p, *r, i, "normal", 0), 0.0f);
    EXPECT_EQ(attrAt<float>(p, *r, i, "normal", 1), 0.6f);
    EXPECT_EQ(attrAt<float>(p, *r, i, "normal", 2), -0.8f);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, i, "intensity"), 40000 + i);
  }
}

TEST(PlyReader, EveryScalarTypeKeptWithItsName) {
  for (bool big : {false, true}) {
    std::string s = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 1\n"
                    "property char a\nproperty uchar b\nproperty short c\nproperty ushort d\n"
                    "property int e\nproperty uint f\nproperty float g\nproperty double h\n"
                    "property int8 i\nproperty float64 j\n"
                    "property float x\nproperty float y\nproperty float z\nend_header\n";
    put(s, int8_t(-100), big);
    put(s, uint8_t(200), big);
    put(s, int16_t(-30000), big);
    put(s, uint16_t(60000), big);
    put(s, int32_t(-2000000000), big);
    put(s, uint32_t(4000000000u), big);
    put(s, 1.25f, big);
    put(s, -2.5e300, big);
    put(s, int8_t(5), big);
    put(s, 0.1, big);
    put(s, 1.0f, big);
    put(s, 2.0f, big);
    put(s, 3.0f, big);
    auto r = openPly(source(s));
    const PointLayout& l = r->header().layout;
    ASSERT_EQ(l.size(), 10u);
    const ScalarType types[] = {ScalarType::I8,  ScalarType::U8,  ScalarType::I16, ScalarType::U16,
                                ScalarType::I32, ScalarType::U32, ScalarType::F32, ScalarType::F64,
                                ScalarType::I8,  ScalarType::F64};
    for (size_t k = 0; k < l.size(); ++k) {
      EXPECT_EQ(l[k].name, std::string(1, char('a' + k)));
      EXPECT_EQ(l[k].type, types[k]);
    }
    Points p = readAll(*r);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p.xyz, (std::vector<double>{1, 2, 3}));
    EXPECT_EQ(attrAt<int8_t>(p, *r, 0, "a"), -100);
    EXPECT_EQ(attrAt<uint8_t>(p, *r, 0, "b"), 200);
    EXPECT_EQ(attrAt<int16_t>(p, *r, 0, "c"), -30000);
    EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "d"), 60000);
    EXPECT_EQ(attrAt<int32_t>(p, *r, 0, "e"), -2000000000);
    EXPECT_EQ(attrAt<uint32_t>(p, *r, 0, "f"), 4000000000u);
    EXPECT_EQ(attrAt<float>(p, *r, 0, "g"), 1.25f);
    EXPECT_EQ(attrAt<double>(p, *r, 0, "h"), -2.5e300);
    EXPECT_EQ(attrAt<int8_t>(p, *r, 0, "i"), 5);
    EXPECT_EQ(attrAt<double>(p, *r, 0, "j"), 0.1);
  }
}

// A mesh whose faces come first: the vertices are found only by walking every face's list.
std::string facesFirst(bool big) {
  std::string s = std::string("ply\nformat ") +
                  (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\n"
                  "element face 3\n"
                  "property list uchar int vertex_indices\n"
                  "property uchar flags\n"
                  "property list ushort float uv\n"
                  "element vertex 2\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  "element edge 1\n"
                  "property int vertex1\nproperty int vertex2\n"
                  "end_header\n";
  const int lengths[3] = {3, 0, 7};
  for (int f = 0; f < 3; ++f) {
    put(s, uint8_t(lengths[f]), big);
    for (int k = 0; k < lengths[f]; ++k) put(s, int32_t(k), big);
    put(s, uint8_t(0xAA), big);
    put(s, uint16_t(f), big);
    for (int k = 0; k < f; ++k) put(s, 0.5f, big);
  }
  put(s, 1.0f, big), put(s, 2.0f, big), put(s, 3.0f, big);
  put(s, -1.0f, big), put(s, -2.0f, big), put(s, -3.0f, big);
  put(s, int32_t(0), big), put(s, int32_t(1), big);
  return s;
}

TEST(PlyReader, BinaryListElementBeforeVertices) {
  for (bool big : {false, true}) {
    auto r = openPly(source(facesFirst(big)));
    EXPECT_EQ(r->header().declaredPoints, 2u);
    EXPECT_EQ(r->header().layout.size(), 0u);
    EXPECT_EQ(r->header().details["elements"][0]["name"], "face");
    EXPECT_EQ(r->header().details["elements"][0]["count"], 3);
    Points p = readAll(*r);
    EXPECT_EQ(p.xyz, (std::vector<double>{1, 2, 3, -1, -2, -3})) << "big endian " << big;
    EXPECT_TRUE(r->warnings().empty()) << r->warnings()[0];
  }
}

TEST(PlyReader, AsciiFacesBeforeAndAfterVertices) {
  const std::string ply =
      "ply\nformat ascii 1.0\n"
      "element face 2\nproperty list uchar int vertex_indices\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property list uchar float tex\n"
      "element material 1\nproperty float shine\n"
      "end_header\n"
      "3 0 1 2\n"
      "4 0 1 2 3\n"
      "1 2 3 2 0.5 0.5\n"
      "4 5 6 0\n"
      "0.25\n";
  auto r = openPly(source(ply));
  Points p = readAll(*r);
  EXPECT_EQ(p.xyz, (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_TRUE(r->warnings().empty());
  EXPECT_EQ(r->header().details["skippedVertexLists"][0], "tex");
}

TEST(PlyReader, BinaryListInsideVertexElement) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
      "property float x\nproperty list uchar short tags\nproperty float y\nproperty float z\n"
      "property uchar quality\nend_header\n";
  for (int i = 0; i < 3; ++i) {
    put(s, float(i));
    put(s, uint8_t(i));
    for (int k = 0; k < i; ++k) put(s, int16_t(-1));
    put(s, float(10 * i));
    put(s, float(100 * i));
    put(s, uint8_t(42 + i));
  }
  auto r = openPly(source(s));
  Points p = readAll(*r, 2);
  EXPECT_EQ(p.xyz, (std::vector<double>{0, 0, 0, 1, 10, 100, 2, 20, 200}));
  EXPECT_EQ(attrAt<uint8_t>(p, *r, 2, "quality"), 44);

  // Cut inside the last record: an error, or the two complete records in lenient mode.
  const std::string cut = s.substr(0, s.size() - 3);
  Error e = errorOf([&] { readAll(*openPly(source(cut, "cut.ply"))); });
  EXPECT_EQ(e.file(), "cut.ply");
  ReadOptions lenient;
  lenient.lenient = true;
  auto l = openPly(source(cut, "cut.ply"), lenient);
  EXPECT_EQ(readAll(*l).size(), 2u);
  EXPECT_TRUE(anyContains(l->warnings(), "only 2 complete"));
}

TEST(PlyReader, TruncatedBinaryNamesFileCountsAndOffset) {
  const std::string s = binaryFloatRgb(10, 7, /*withTail=*/true);
  const size_t headerBytes = s.size() - 7 * 15 - 3;
  Error e = errorOf([&] { openPly(source(s, "/scans/cut.ply")); });
  EXPECT_EQ(e.file(), "/scans/cut.ply");
  EXPECT_EQ(e.position(), Error::atByte(headerBytes + 7 * 15));
  EXPECT_NE(e.reason().find("declares 10 vertices"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("only 7 complete"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("/scans/cut.ply"), std::string::npos);
}

TEST(PlyReader, LenientKeepsCompleteRecords) {
  ReadOptions o;
  o.lenient = true;
  auto r = openPly(source(binaryFloatRgb(10, 7, true)), o);
  EXPECT_EQ(r->header().declaredPoints, 10u);
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("only 7 complete"), std::string::npos);
  Points p = readAll(*r);
  ASSERT_EQ(p.size(), 7u);
  EXPECT_EQ(p.xyz[3 * 6], 6.5);
  EXPECT_EQ(r->warnings().size(), 1u);

  // Ascii: the cut shows only when reading; a short last line is part of the cut.
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n1 2 3\n4 5 6\n7 8";
  Error e = errorOf([&] { readAll(*openPly(source(ascii, "a.ply"))); });
  EXPECT_EQ(e.file(), "a.ply");
  EXPECT_EQ(e.position(), Error::atLine(10));
  EXPECT_NE(e.reason().find("declares 4 vertices"), std::string::npos) << e.what();
  auto a = openPly(source(ascii, "a.ply"), o);
  Points q = readAll(*a);
  EXPECT_EQ(q.xyz, (std::vector<double>{1, 2, 3, 4, 5, 6}));
  EXPECT_TRUE(anyContains(a->warnings(), "only 2 complete"));
}

TEST(PlyReader, HeaderDeclaringTooFewVerticesWarns) {
  auto r = openPly(source(binaryFloatRgb(3, 5)));
  Points p = readAll(*r);
  EXPECT_EQ(p.size(), 3u);
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("30 bytes follow"), std::string::npos) << r->warnings()[0];
  EXPECT_NE(r->warnings()[0].find("room for 2 more vertices"), std::string::npos);

  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n1 2 3\n4 5 6\n7 8 9\n\n";
  auto a = openPly(source(ascii));
  EXPECT_EQ(readAll(*a).size(), 1u);
  EXPECT_TRUE(anyContains(a->warnings(), "2 lines follow"));
}

TEST(PlyReader, AbsurdVertexCountAllocatesNothingLarge) {
  // 2^60 vertices of 15 bytes: far more than any file; the reader must neither allocate for
  // them nor overflow computing their size.
  const std::string s = binaryFloatRgb(uint64_t(1) << 60, 2);
  Error e = errorOf([&] { openPly(source(s)); });
  EXPECT_NE(e.reason().find("only 2 complete"), std::string::npos);
  ReadOptions o;
  o.lenient = true;
  auto r = openPly(source(s), o);
  PointBatch b;
  ASSERT_TRUE(r->read(b, std::numeric_limits<size_t>::max()));
  EXPECT_EQ(b.size(), 2u);
  EXPECT_FALSE(r->read(b, std::numeric_limits<size_t>::max()));

  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 18446744073709551615\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n1 2 3\n";
  auto a = openPly(source(ascii), o);
  ASSERT_TRUE(a->read(b, std::numeric_limits<size_t>::max()));
  EXPECT_EQ(b.size(), 1u);
  EXPECT_LE(b.xyz.capacity(), 64u);
  EXPECT_FALSE(a->read(b, 1000));
  EXPECT_FALSE(errorOf([&] { readAll(*openPly(source(ascii))); }).reason().empty());

  // A face list that claims 2^31 items before the vertices.
  std::string f =
      "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list int int idx\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  put(f, int32_t(0x7fffffff));
  put(f, 1.0f), put(f, 2.0f), put(f, 3.0f);
  EXPECT_NE(errorOf([&] { openPly(source(f)); }).reason().find("inside element 'face'"),
            std::string::npos);
}

TEST(PlyReader, MalformedFilesAreErrors) {
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  struct Case {
    std::string bytes, expect;
  } cases[] = {
      {"", "empty file"},
      {"plx\nformat ascii 1.0\n", "not a PLY file"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz, "no 'end_header'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
       "unknown property type 'float128'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\n"
       "end_header\n1 2\n",
       "no scalar property 'x'"},
      {"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int i\nend_header\n",
       "no 'vertex' element"},
      {"ply\nformat utf8 1.0\nend_header\n", "unknown encoding"},
      {"ply\nformat ascii 2.0\nend_header\n", "unsupported PLY version"},
      {"ply\nelement vertex 1\n" + xyz + "end_header\n1 2 3\n", "no 'format' line"},
      {"ply\nformat ascii 1.0\nelement vertex -1\n" + xyz + "end_header\n", "bad element count"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "before any element"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "property float x\nend_header\n",
       "a second property 'x'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\nend_header\n",
       "list count of type 'float'"},
      {"ply\nformat ascii 1.0\nbogus\nend_header\n", "unknown keyword 'bogus'"},
  };
  for (const auto& c : cases) {
    Error e = errorOf([&] { readAll(*openPly(source(c.bytes, "bad.ply"))); });
    EXPECT_EQ(e.file(), "bad.ply");
    EXPECT_NE(e.reason().find(c.expect), std::string::npos)
        << "expected '" << c.expect << "' in: " << e.what();
  }
}

TEST(PlyReader, BadAsciiNumberNamesLineAndToken) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
      "end_header\n"
      "1 2 3 4 5 6\n"
      "1 2 3.4.5 4 5 6\n";
  Error e = errorOf([&] { readAll(*openPly(source(ply, "n.ply"))); });
  EXPECT_EQ(e.file(), "n.ply");
  EXPECT_EQ(e.position(), "line 12");
  EXPECT_NE(e.reason().find("'3.4.5'"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("property 'z'"), std::string::npos) << e.what();

  // 256 is no uchar; a missing value and an extra one are errors too.
  for (const char* line : {"1 2 3 256 0 0\n1 2 3 4 5 6\n", "1 2 3 4 5\n1 2 3 4 5 6\n",
                           "1 2 3 4 5 6 7\n1 2 3 4 5 6\n"}) {
    std::string bad = ply.substr(0, ply.find("end_header\n") + 11) + line + "1 2 3 4 5 6\n";
    Error b = errorOf([&] { readAll(*openPly(source(bad))); });
    EXPECT_EQ(b.position(), "line 11") << b.what();
  }
}

TEST(PlyReader, ColourNormalIntensityAndAlphaMapping) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
      "property double normal_x\nproperty double normal_y\nproperty double normal_z\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\n"
      "property uchar alpha\nproperty float scalar_intensity\nproperty float rgb\n"
      "end_header\n";
  for (int i = 0; i < 2; ++i) {
    put(s, 0.0), put(s, 0.0), put(s, i ? -1.0 : 1.0);
    put(s, 1.0f), put(s, 2.0f), put(s, 3.0f);
    put(s, 0.0f), put(s, 0.5f), put(s, i ? 1.5f : 1.0f);
    put(s, uint8_t(128));
    put(s, 0.75f);
    put(s, 9.0f);
  }
  auto r = openPly(source(s));
  const PointLayout& l = r->header().layout;
  EXPECT_EQ(r->header().rgbBits, 16);
  ASSERT_EQ(l.size(), 5u);
  EXPECT_EQ(l[0], (Attribute{"normal", ScalarType::F32, 3, ""}));
  EXPECT_EQ(l[1], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(l[2], (Attribute{"alpha", ScalarType::U8, 1, ""}));
  EXPECT_EQ(l[3], (Attribute{"intensity", ScalarType::F32, 1, ""}));
  // A scalar named "rgb" (PCL's packed colour) must not pass for the uint16 x3 colour.
  EXPECT_EQ(l[4], (Attribute{"ply_rgb", ScalarType::F32, 1, ""}));
  Points p = readAll(*r);
  EXPECT_EQ(attrAt<float>(p, *r, 1, "normal", 2), -1.0f);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 0), 0);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 1), 32768);  // round(0.5 * 65535), ties to even
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 0, "rgb", 2), 65535);
  EXPECT_EQ(attrAt<uint16_t>(p, *r, 1, "rgb", 2), 65535);  // 1.5 clamped, and counted
  EXPECT_EQ(attrAt<uint8_t>(p, *r, 1, "alpha"), 128);
  EXPECT_EQ(attrAt<float>(p, *r, 1, "intensity"), 0.75f);
  EXPECT_TRUE(anyContains(r->warnings(), "1 colour values outside [0, 1]"));
}

TEST(PlyReader, CrsFromComment) {
  const std::string tail =
      "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  auto a =
      openPly(source("ply\nformat ascii 1.0\ncomment crs: PROJCS[\"CH1903+ / LV95\"]\n" + tail));
  EXPECT_EQ(a->header().crs["wkt"], "PROJCS[\"CH1903+ / LV95\"]");
  auto b = openPly(source("ply\nformat ascii 1.0\ncomment srs EPSG:2056\n" + tail));
  EXPECT_EQ(b->header().crs["epsg"], 2056);
  auto c = openPly(source("ply\nformat ascii 1.0\ncomment scanned in 2019\n" + tail));
  EXPECT_TRUE(c->header().crs.is_null());
  PointBatch batch;
  EXPECT_FALSE(c->read(batch, 10));
}

TEST(PlyReader, OpenReaderChoosesPlyByExtension) {
  TempDir dir;
  test::writeFile(dir.file("a.PLY"), binaryFloatRgb(4, 4));
  auto r = openReader(dir.file("a.PLY"));
  EXPECT_EQ(r->header().format, "ply");
  EXPECT_EQ(r->header().path, dir.file("a.PLY"));
  EXPECT_EQ(readAll(*r).size(), 4u);
}

// Points with one attribute of every scalar type, a colour, a normal and a 2-component vector.
struct Sample {
  SourceHeader header;
  PointBatch batch;
};

Sample sample(int rgbBits) {
  Sample s;
  s.header.rgbBits = rgbBits;
  s.header.crs = {{"wkt", "GEOGCS[\"WGS 84\"]"}};
  PointLayout& l = s.header.layout;
  l.add({"rgb", ScalarType::U16, 3, ""});
  l.add({"normal", ScalarType::F32, 3, ""});
  const ScalarType types[] = {ScalarType::U8,  ScalarType::I8,  ScalarType::U16, ScalarType::I16,
                              ScalarType::U32, ScalarType::I32, ScalarType::U64, ScalarType::I64,
                              ScalarType::F32, ScalarType::F64};
  for (ScalarType t : types) l.add({std::string("v_") + scalarName(t), t, 1, ""});
  l.add({"intensity", ScalarType::U16, 1, ""});
  l.add({"dir", ScalarType::F32, 2, ""});
  const int n = 50;
  s.batch.attrs.resize(n * l.stride());
  for (int i = 0; i < n; ++i) {
    s.batch.xyz.push_back(2600000.0 + i * 0.001);
    s.batch.xyz.push_back(-1200000.123456789 * (i + 1));
    s.batch.xyz.push_back(i == 3 ? -0.0 : 1e-300 * i);
    uint8_t* a = s.batch.attrs.data() + i * l.stride();
    for (size_t k = 0; k < l.size(); ++k) {
      for (uint32_t c = 0; c < l[k].components; ++c) {
        double v = (i * 37 + k * 11 + c * 5) % 200 - (isSigned(l[k].type) ? 100 : 0);
        if (l[k].name == "rgb") v = rgbBits == 8 ? 257.0 * ((i * 31 + c) % 256) : i * 1311 + c;
        if (l[k].name == "normal") v = c == 2 ? 1.0 : 0.0;
        if (isFloat(l[k].type)) v += 0.1;
        storeFromDouble(l[k].type, v, a + l.offset(k) + c * scalarSize(l[k].type));
      }
    }
  }
  // Extremes that must survive: the ends of the 64-bit ranges do not fit in a double.
  const uint64_t u64 = std::numeric_limits<uint64_t>::max() - 1;
  const int64_t i64 = std::numeric_limits<int64_t>::min() + 1;
  std::memcpy(s.batch.attrs.data() + l.offset(size_t(l.find("v_uint64"))), &u64, 8);
  std::memcpy(s.batch.attrs.data() + l.offset(size_t(l.find("v_int64"))), &i64, 8);
  return s;
}

TEST(PlyWriter, RoundTripEveryTypeBinaryAndAscii) {
  TempDir dir;
  for (int rgbBits : {8, 16}) {
    for (bool ascii : {false, true}) {
      SCOPED_TRACE("rgbBits " + std::to_string(rgbBits) + (ascii ? " ascii" : " binary"));
      Sample s = sample(rgbBits);
      const std::string path = dir.file("rt.ply");
      auto w = createPlyWriter(path, s.header, ascii);
      // Two batches, to check that the count covers both.
      PointBatch first, second;
      const size_t stride = s.header.layout.stride(), half = 20;
      first.xyz.assign(s.batch.xyz.begin(), s.batch.xyz.begin() + 3 * half);
      first.attrs.assign(s.batch.attrs.begin(), s.batch.attrs.begin() + half * stride);
      second.xyz.assign(s.batch.xyz.begin() + 3 * half, s.batch.xyz.end());
      second.attrs.assign(s.batch.attrs.begin() + half * stride, s.batch.attrs.end());
      w->write(first);
      w->write(second);
      w->close();

      auto r = openReader(path);
      const SourceHeader& h = r->header();
      EXPECT_EQ(h.details["encoding"], ascii ? "ascii" : "binary_little_endian");
      EXPECT_EQ(h.declaredPoints, 50u);
      EXPECT_EQ(h.rgbBits, rgbBits);
      EXPECT_EQ(h.crs, s.header.crs);
      EXPECT_TRUE(r->warnings().empty());
      // Every attribute but the vector comes back as it was; the vector as dir_0, dir_1.
      const PointLayout& in = s.header.layout;
      ASSERT_EQ(h.layout.size(), in.size() + 1);
      for (size_t k = 0; k + 1 < in.size(); ++k) EXPECT_EQ(h.layout[k], in[k]);
      EXPECT_EQ(h.layout[in.size() - 1], (Attribute{"dir_0", ScalarType::F32, 1, ""}));
      EXPECT_EQ(h.layout[in.size()], (Attribute{"dir_1", ScalarType::F32, 1, ""}));
      Points p = readAll(*r, 16);
      ASSERT_EQ(p.size(), 50u);
      // Bitwise: -0.0 and 1e-300 must come back exactly.
      EXPECT_EQ(std::memcmp(p.xyz.data(), s.batch.xyz.data(), p.xyz.size() * 8), 0);
      EXPECT_EQ(p.attrs, s.batch.attrs);  // dir_0, dir_1 lie where dir's components were
      EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
    }
  }
}

TEST(PlyWriter, AppearsOnlyAtClose) {
  TempDir dir;
  Sample s = sample(16);
  const std::string path = dir.file("atomic.ply");
  {
    auto w = createPlyWriter(path, s.header);
    w->write(s.batch);
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_TRUE(std::filesystem::exists(path + ".tmp"));
  }
  // Destroyed without close(): an interrupted export leaves nothing behind.
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));

  auto w = createPlyWriter(path, s.header);
  w->close();  // no points: a valid empty file
  auto r = openReader(path);
  PointBatch b;
  EXPECT_FALSE(r->read(b, 100));
  EXPECT_EQ(r->header().declaredPoints, 0u);
}

// Real data: a scan with double positions, uchar colour and float normals.
TEST(PlyReader, RealLionWithNormals) {
  NL_REQUIRE_SHARED("scans/lion_takanawa_normals.ply");
  auto r = openReader((test::sharedData() / "scans/lion_takanawa_normals.ply").string());
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.declaredPoints, 341989u);
  EXPECT_EQ(h.rgbBits, 8);
  EXPECT_EQ(h.details["encoding"], "binary_little_endian");
  ASSERT_EQ(h.layout.size(), 2u);
  EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"normal", ScalarType::F32, 3, ""}));
  Points p = readAll(*r, 100000);
  ASSERT_EQ(p.size(), 341989u);
  size_t notUnit = 0, notByte = 0;
  Box3d box;
  for (size_t i = 0; i < p.size(); ++i) {
    box.extend(p.xyz[3 * i], p.xyz[3 * i + 1], p.xyz[3 * i + 2]);
    const float nx = attrAt<float>(p, *r, i, "normal", 0),
                ny = attrAt<float>(p, *r, i, "normal", 1),
                nz = attrAt<float>(p, *r, i, "normal", 2);
    if (std::fabs(std::sqrt(nx * nx + ny * ny + nz * nz) - 1.0f) > 1e-2f) ++notUnit;
    for (int c = 0; c < 3; ++c)
      if (attrAt<uint16_t>(p, *r, i, "rgb", c) % 257 != 0) ++notByte;
  }
  EXPECT_EQ(notUnit, 0u);
  EXPECT_EQ(notByte, 0u);
  EXPECT_FALSE(box.empty());
  EXPECT_TRUE(r->warnings().empty());
  EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());
}

// Real data: an ascii mesh whose faces follow the vertices.
TEST(PlyReader, RealBunnyAscii) {
  NL_REQUIRE_SHARED("meshes/bunny.ply");
  auto r = openReader((test::sharedData() / "meshes/bunny.ply").string());
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.details["encoding"], "ascii");
  EXPECT_EQ(h.declaredPoints, 35947u);
  EXPECT_EQ(h.rgbBits, 0);
  ASSERT_EQ(h.layout.size(), 2u);
  EXPECT_EQ(h.layout[0], (Attribute{"confidence", ScalarType::F32, 1, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"intensity", ScalarType::F32, 1, ""}));
  Points p = readAll(*r, 10000);
  ASSERT_EQ(p.size(), 35947u);
  // The first vertex line: -0.0378297 0.12794 0.00447467 0.850855 0.5
  EXPECT_EQ(p.xyz[0], double(-0.0378297f));
  EXPECT_EQ(p.xyz[1], double(0.12794f));
  EXPECT_EQ(attrAt<float>(p, *r, 0, "confidence"), 0.850855f);
  EXPECT_EQ(attrAt<float>(p, *r, 0, "intensity"), 0.5f);
  Box3d box;
  for (size_t i = 0; i < p.size(); ++i)
    box.extend(p.xyz[3 * i], p.xyz[3 * i + 1], p.xyz[3 * i + 2]);
  EXPECT_TRUE(box.contains(0, 0.1, 0));
  EXPECT_LT(box.max.x - box.min.x, 0.2);                   // a bunny about 15 cm long
  EXPECT_TRUE(r->warnings().empty()) << r->warnings()[0];  // the 69,451 faces are all there
}

// Real data: a binary mesh with colour, alpha and normals, whose faces follow the vertices.
TEST(PlyReader, RealGargoyleBinaryWithFacesAfter) {
  NL_REQUIRE_SHARED("meshes/gargoyle.ply");
  auto r = openReader((test::sharedData() / "meshes/gargoyle.ply").string());
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.declaredPoints, 25002u);
  EXPECT_EQ(h.rgbBits, 8);
  ASSERT_EQ(h.layout.size(), 3u);
  EXPECT_EQ(h.layout[0], (Attribute{"normal", ScalarType::F32, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[2], (Attribute{"alpha", ScalarType::U8, 1, ""}));
  EXPECT_EQ(h.details["elements"][1]["name"], "face");
  EXPECT_EQ(h.details["elements"][1]["count"], 50000);
  Points p = readAll(*r, 4096);
  EXPECT_EQ(p.size(), 25002u);
  // Walking the 50,000 faces after the vertices ends exactly at the end of the file.
  EXPECT_TRUE(r->warnings().empty()) << r->warnings()[0];
}

}  // namespace
}  // namespace nestlight
