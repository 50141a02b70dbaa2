// PCD reader (openPcd, through PCL): hand-written ascii and binary files checked value by value,
// malformed files, and a real organised Kinect capture from ../shared/data.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight {
namespace {

using test::errorOf;
using test::TempDir;
using test::writeFile;

template <typename T>
T attrAt(const PointBatch& b, const PointReader& r, size_t point, std::string_view name,
         int component = 0) {
  const PointLayout& l = r.header().layout;
  const int idx = l.find(name);
  EXPECT_GE(idx, 0) << name;
  T v;
  std::memcpy(&v,
              b.attrs.data() + point * l.stride() + l.offset(size_t(idx)) + component * sizeof(T),
              sizeof(T));
  return v;
}

std::vector<PointBatch> readBatches(PointReader& r, size_t batchSize) {
  std::vector<PointBatch> out;
  PointBatch b;
  while (r.read(b, batchSize)) out.push_back(b);
  return out;
}

float packedFloat(uint32_t bits) {
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

std::string asciiPcd() {
  // Packed colour 0x00FF8040 in a float, the way PCL writes PointXYZRGB; r >= 0x80 keeps the
  // float normal (a denormal would not survive text parsing).
  char rgb[64];
  std::snprintf(rgb, sizeof rgb, "%.9g", double(packedFloat(0x00FF8040u)));
  return std::string(
             "# .PCD v0.7 - Point Cloud Data file format\n"
             "VERSION 0.7\n"
             "FIELDS x y z rgb intensity\n"
             "SIZE 4 4 4 4 4\n"
             "TYPE F F F F F\n"
             "COUNT 1 1 1 1 1\n"
             "WIDTH 3\n"
             "HEIGHT 1\n"
             "VIEWPOINT 1 2 3 1 0 0 0\n"
             "POINTS 3\n"
             "DATA ascii\n"
             "1.5 -2.25 3 ") +
         rgb + " 0.5\nnan nan nan " + rgb + " 7\n-4 8.125 0.25 " + rgb + " 1234.5\n";
}

#pragma pack(push, 1)
struct BinRecord {
  double x, y, z;
  uint32_t rgba;
  float nx, ny, nz, curvature;
  uint32_t label;
  float pad;  // "_"
  int16_t extra[2];
};
#pragma pack(pop)

const char* kBinaryHeader =
    "# .PCD v0.7 - Point Cloud Data file format\n"
    "VERSION 0.7\n"
    "FIELDS x y z rgba normal_x normal_y normal_z curvature label _ extra\n"
    "SIZE 8 8 8 4 4 4 4 4 4 4 2\n"
    "TYPE F F F U F F F F U F I\n"
    "COUNT 1 1 1 1 1 1 1 1 1 1 2\n"
    "WIDTH 2\n"
    "HEIGHT 2\n"
    "VIEWPOINT 0 0 0 1 0 0 0\n"
    "POINTS 4\n"
    "DATA binary\n";

std::vector<BinRecord> binRecords() {
  const double nan = std::nan("");
  return {
      {500000.125, 5000000.5, 101.25, 0x80102030u, 0, 0, 1, 0.01f, 7, 0, {-3, 4}},
      {nan, nan, nan, 0xFFFFFFFFu, 0, 1, 0, 0.02f, 8, 0, {5, -6}},
      {-1, -2, -3, 0x40000000u, 1, 0, 0, 0.03f, 9, 0, {7, 8}},
      {0.5, 0.25, 0.125, 0x00ABCDEFu, 0.6f, 0.8f, 0, 0.04f, 10, 0, {9, 10}},
  };
}

std::string binaryPcd(size_t dropBytes = 0) {
  std::string s = kBinaryHeader;
  auto recs = binRecords();
  s.append(reinterpret_cast<const char*>(recs.data()), recs.size() * sizeof(BinRecord));
  s.resize(s.size() - dropBytes);
  return s;
}

TEST(PcdReader, AsciiValuesExact) {
  TempDir dir;
  const std::string path = dir.file("a.pcd");
  writeFile(path, asciiPcd());
  auto r = openPcd(path);
  const SourceHeader& h = r->header();
  EXPECT_EQ(h.format, "pcd");
  ASSERT_TRUE(h.declaredPoints.has_value());
  EXPECT_EQ(*h.declaredPoints, 3u);
  EXPECT_EQ(h.rgbBits, 8);
  ASSERT_EQ(h.layout.size(), 2u);
  EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"intensity", ScalarType::F32, 1, ""}));  // PCL's type kept
  EXPECT_EQ(h.details["data"], "ascii");
  EXPECT_EQ(h.details["finite_points"], 2);
  EXPECT_EQ(h.details["nan_points"], 1);
  EXPECT_EQ(h.details["organized"], false);
  EXPECT_EQ(h.details["sensor_origin"], nlohmann::json({1.0, 2.0, 3.0}));
  EXPECT_EQ(h.details["sensor_orientation"], nlohmann::json({1.0, 0.0, 0.0, 0.0}));

  auto batches = readBatches(*r, 1000);
  ASSERT_EQ(batches.size(), 1u);
  const PointBatch& b = batches[0];
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b.xyz[0], 1.5);
  EXPECT_EQ(b.xyz[1], -2.25);
  EXPECT_EQ(b.xyz[2], 3.0);
  EXPECT_TRUE(std::isnan(b.xyz[3]) && std::isnan(b.xyz[4]) && std::isnan(b.xyz[5]));
  EXPECT_EQ(b.xyz[6], -4.0);
  EXPECT_EQ(b.xyz[7], 8.125);
  EXPECT_EQ(b.xyz[8], 0.25);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(attrAt<uint16_t>(b, *r, i, "rgb", 0), 255 * 257);
    EXPECT_EQ(attrAt<uint16_t>(b, *r, i, "rgb", 1), 128 * 257);
    EXPECT_EQ(attrAt<uint16_t>(b, *r, i, "rgb", 2), 64 * 257);
  }
  EXPECT_EQ(attrAt<float>(b, *r, 0, "intensity"), 0.5f);
  EXPECT_EQ(attrAt<float>(b, *r, 1, "intensity"), 7.0f);
  EXPECT_EQ(attrAt<float>(b, *r, 2, "intensity"), 1234.5f);
}

TEST(PcdReader, BinaryAnyFieldsExact) {
  TempDir dir;
  const std::string path = dir.file("b.pcd");
  writeFile(path, binaryPcd());
  auto r = openPcd(path);
  const SourceHeader& h = r->header();
  EXPECT_EQ(*h.declaredPoints, 4u);
  EXPECT_EQ(h.details["data"], "binary");
  EXPECT_EQ(h.details["organized"], true);
  EXPECT_EQ(h.details["width"], 2);
  EXPECT_EQ(h.details["height"], 2);
  EXPECT_EQ(h.details["finite_points"], 3);
  EXPECT_EQ(h.details["nan_points"], 1);
  // rgb, normal, then the other fields in file order; "_" dropped; alpha varies, so it is kept.
  ASSERT_EQ(h.layout.size(), 6u);
  EXPECT_EQ(h.layout[0], (Attribute{"rgb", ScalarType::U16, 3, ""}));
  EXPECT_EQ(h.layout[1], (Attribute{"normal", ScalarType::F32, 3, ""}));
  EXPECT_EQ(h.layout[2], (Attribute{"curvature", ScalarType::F32, 1, ""}));
  EXPECT_EQ(h.layout[3], (Attribute{"label", ScalarType::U32, 1, ""}));
  EXPECT_EQ(h.layout[4], (Attribute{"extra", ScalarType::I16, 2, ""}));
  EXPECT_EQ(h.layout[5], (Attribute{"alpha", ScalarType::U8, 1, ""}));

  // Batches of 1 and rewind give the same values.
  for (size_t batchSize : {size_t(1), size_t(3), size_t(100)}) {
    r->rewind();
    std::vector<double> xyz;
    std::vector<uint8_t> attrs;
    PointBatch b;
    while (r->read(b, batchSize)) {
      EXPECT_LE(b.size(), batchSize);
      xyz.insert(xyz.end(), b.xyz.begin(), b.xyz.end());
      attrs.insert(attrs.end(), b.attrs.begin(), b.attrs.end());
    }
    PointBatch all;
    all.xyz = xyz;
    all.attrs = attrs;
    ASSERT_EQ(all.size(), 4u);
    const auto recs = binRecords();
    for (size_t i = 0; i < 4; ++i) {
      const BinRecord& rec = recs[i];
      if (i == 1) {
        EXPECT_TRUE(std::isnan(all.xyz[3]));
      } else {
        EXPECT_EQ(all.xyz[i * 3 + 0], rec.x);
        EXPECT_EQ(all.xyz[i * 3 + 1], rec.y);
        EXPECT_EQ(all.xyz[i * 3 + 2], rec.z);
      }
      EXPECT_EQ(attrAt<uint16_t>(all, *r, i, "rgb", 0), ((rec.rgba >> 16) & 0xff) * 257);
      EXPECT_EQ(attrAt<uint16_t>(all, *r, i, "rgb", 1), ((rec.rgba >> 8) & 0xff) * 257);
      EXPECT_EQ(attrAt<uint16_t>(all, *r, i, "rgb", 2), (rec.rgba & 0xff) * 257);
      EXPECT_EQ(attrAt<uint8_t>(all, *r, i, "alpha"), rec.rgba >> 24);
      EXPECT_EQ(attrAt<float>(all, *r, i, "normal", 0), rec.nx);
      EXPECT_EQ(attrAt<float>(all, *r, i, "normal", 1), rec.ny);
      EXPECT_EQ(attrAt<float>(all, *r, i, "normal", 2), rec.nz);
      EXPECT_EQ(attrAt<float>(all, *r, i, "curvature"), rec.curvature);
      EXPECT_EQ(attrAt<uint32_t>(all, *r, i, "label"), rec.label);
      EXPECT_EQ(attrAt<int16_t>(all, *r, i, "extra", 0), rec.extra[0]);
      EXPECT_EQ(attrAt<int16_t>(all, *r, i, "extra", 1), rec.extra[1]);
    }
  }
}

TEST(PcdReader, TruncatedBinaryIsAnError) {
  TempDir dir;
  const std::string path = dir.file("t.pcd");
  writeFile(path, binaryPcd(10));
  try {
    openPcd(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.reason().find("truncated"), std::string::npos) << e.what();
    const size_t complete = std::strlen(kBinaryHeader) + 3 * sizeof(BinRecord);
    EXPECT_EQ(e.position(), Error::atByte(complete));
  }
}

TEST(PcdReader, TruncatedBinaryLenientKeepsCompletePoints) {
  TempDir dir;
  const std::string path = dir.file("t.pcd");
  writeFile(path, binaryPcd(10));
  ReadOptions o;
  o.lenient = true;
  auto r = openPcd(path, o);
  ASSERT_EQ(r->warnings().size(), 1u);
  EXPECT_NE(r->warnings()[0].find("truncated"), std::string::npos);
  EXPECT_EQ(*r->header().declaredPoints, 4u);
  PointBatch b;
  ASSERT_TRUE(r->read(b, 100));
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b.xyz[6], -1.0);
  EXPECT_FALSE(r->read(b, 100));
}

TEST(PcdReader, TruncatedAsciiIsAnError) {
  TempDir dir;
  const std::string path = dir.file("t.pcd");
  std::string s = asciiPcd();
  s.resize(s.rfind("-4 8.125"));  // drop the last line
  writeFile(path, s);
  try {
    openPcd(path);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.position(), Error::atLine(14)) << e.what();
    EXPECT_NE(e.reason().find("truncated"), std::string::npos) << e.what();
  }
  ReadOptions o;
  o.lenient = true;
  auto r = openPcd(path, o);
  EXPECT_EQ(r->warnings().size(), 1u);
  PointBatch b;
  ASSERT_TRUE(r->read(b, 100));
  EXPECT_EQ(b.size(), 2u);
}

// PCL's own ascii parser reads these as zeros without an error; ours names the line.
TEST(PcdReader, MalformedAsciiValuesAreErrors) {
  TempDir dir;
  const std::string head =
      "VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 1\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\n"
      "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n";
  const std::pair<const char*, const char*> cases[] = {
      {"1 2 3 4\n4 5 abc 6\n", "'abc' of field 'z'"},
      {"1 2 3 4\n4 5 6\n", "expected 4 values, found 3"},
      {"1 2 3 4\n4 5 6 7 8\n", "expected 4 values, found 5"},
      {"1 2 3 4\n4 5 6 256\n", "'256' of field 'label'"},  // out of range for uint8
      {"1 2 3 4\n4 5 6 1.5\n", "'1.5' of field 'label'"},
  };
  for (const auto& [data, message] : cases) {
    const std::string path = dir.file("m.pcd");
    writeFile(path, head + data);
    try {
      openPcd(path);
      ADD_FAILURE() << "no error for " << data;
    } catch (const Error& e) {
      EXPECT_EQ(e.position(), Error::atLine(12)) << e.what();
      EXPECT_NE(e.reason().find(message), std::string::npos) << e.what();
    }
  }
  // Extra lines are a header/data disagreement: an error, or a warning when lenient.
  const std::string path = dir.file("extra.pcd");
  writeFile(path, head + "1 2 3 4\n\n4 5 6 7\n8 9 10 11\n");
  EXPECT_THROW(openPcd(path), Error);
  ReadOptions o;
  o.lenient = true;
  auto r = openPcd(path, o);
  EXPECT_EQ(r->warnings().size(), 1u);
  PointBatch b;
  ASSERT_TRUE(r->read(b, 100));
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.xyz[3], 4.0);
  EXPECT_EQ(r->header().details["version"], "0.7");
}

TEST(PcdReader, AsciiDenormalPackedColour) {
  // r < 0x80 makes the packed float a denormal, which text parsers often reject.
  TempDir dir;
  const std::string path = dir.file("d.pcd");
  char rgb[64];
  std::snprintf(rgb, sizeof rgb, "%.9g", double(packedFloat(0x00204080u)));
  writeFile(path, std::string("VERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F\n"
                              "COUNT 1 1 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n0 0 0 ") +
                      rgb + "\n");
  auto r = openPcd(path);
  PointBatch b;
  ASSERT_TRUE(r->read(b, 10));
  EXPECT_EQ(attrAt<uint16_t>(b, *r, 0, "rgb", 0), 0x20 * 257);
  EXPECT_EQ(attrAt<uint16_t>(b, *r, 0, "rgb", 1), 0x40 * 257);
  EXPECT_EQ(attrAt<uint16_t>(b, *r, 0, "rgb", 2), 0x80 * 257);
}

TEST(PcdReader, MalformedFilesAreErrors) {
  TempDir dir;
  const Error missing = errorOf([&] { openPcd(dir.file("missing.pcd")); });
  EXPECT_EQ(missing.file(), dir.file("missing.pcd"));
  EXPECT_NE(missing.reason().find("no such file"), std::string::npos);

  const std::string garbage = dir.file("garbage.pcd");
  writeFile(garbage, "this is not a point cloud\n\x01\x02\x03");
  EXPECT_EQ(errorOf([&] { openPcd(garbage); }).position(), "header");

  // binary_compressed whose block runs past the end of the file.
  std::string shortCompressed =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100\nDATA binary_compressed\n";
  const uint32_t sizes[2] = {500, 1200};
  shortCompressed.append(reinterpret_cast<const char*>(sizes), 8);
  shortCompressed.append(20, '\0');

  struct Case {
    const char* name;
    std::string bytes;
    const char* reason;
  } cases[] = {
      {"noz.pcd",
       "VERSION 0.7\nFIELDS x y intensity\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
       "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "'z'"},
      // A header asking for far more memory than the file could hold: PCL would allocate it.
      {"huge.pcd",
       "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2000000000\n"
       "HEIGHT 1000\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2000000000000\nDATA binary\n1234",
       "implausible"},
      {"c.pcd", shortCompressed, "truncated"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir.file(c.name);
    writeFile(path, c.bytes);
    const Error e = errorOf([&] { openPcd(path); });
    EXPECT_NE(e.reason().find(c.reason), std::string::npos) << e.what();
  }
}

TEST(PcdReader, OpenReaderDispatchesPcd) {
  TempDir dir;
  const std::string path = dir.file("A.PCD");
  writeFile(path, asciiPcd());
  auto r = openReader(path);
  EXPECT_EQ(r->header().format, "pcd");
}

TEST(PcdReader, KinectOrganisedBinaryCompressed) {
  NL_REQUIRE_SHARED("scans/kinect_indoor.pcd");
  const std::string path = (test::sharedData() / "scans/kinect_indoor.pcd").string();
  auto r = openPcd(path);
  const SourceHeader& h = r->header();
  EXPECT_EQ(*h.declaredPoints, 307200u);
  EXPECT_EQ(h.rgbBits, 8);
  EXPECT_EQ(h.details["data"], "binary_compressed");
  EXPECT_EQ(h.details["width"], 640);
  EXPECT_EQ(h.details["height"], 480);
  EXPECT_EQ(h.details["organized"], true);
  EXPECT_EQ(h.details["finite_points"], 259847);
  EXPECT_EQ(h.details["nan_points"], 47353);
  ASSERT_EQ(h.layout.size(), 1u);
  EXPECT_EQ(h.layout[0].name, "rgb");

  for (int pass = 0; pass < 2; ++pass) {  // the second pass after rewind()
    uint64_t finite = 0, nan = 0, total = 0;
    PointBatch b;
    while (r->read(b, 50000)) {
      for (size_t i = 0; i < b.size(); ++i) {
        const double* p = &b.xyz[i * 3];
        if (std::isnan(p[0]) || std::isnan(p[1]) || std::isnan(p[2]))
          ++nan;
        else
          ++finite;
      }
      total += b.size();
    }
    EXPECT_EQ(total, 307200u);
    EXPECT_EQ(finite, 259847u);
    EXPECT_EQ(nan, 47353u);
    EXPECT_EQ(r->bytesConsumed(), r->bytesTotal());
    r->rewind();
  }
}

}  // namespace
}  // namespace nestlight
