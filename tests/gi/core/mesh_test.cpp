// Mesh reading: PLY (ascii, binary of both byte orders) and OBJ written here byte by byte with
// known content and checked value by value; fan triangulation, OBJ's relative indices and
// per-corner normals; degenerate triangles dropped and counted; malformed, truncated and lying
// files rejected with the file and the line or byte; the real bunny and gargoyle.
#include "nestlight/gi/mesh.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "nestlight/octree/error.h"
#include "test_support.h"

using namespace nestlight::gi;
using nestlight::Error;

namespace {

TriangleMesh readBytes(const std::string& name, const std::string& bytes,
                       MeshReadReport* r = nullptr) {
  return readMeshFromMemory(name, bytes.data(), bytes.size(), r);
}

// The Error that reading `bytes` as `name` throws; fails the test if it reads.
Error errorOf(const std::string& name, const std::string& bytes) {
  try {
    readBytes(name, bytes);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << name << " was read without an error";
  return Error("none");
}

// Appends `v` in the given byte order.
template <typename T>
void put(std::string& s, T v, bool big) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big == (std::endian::native == std::endian::little)) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

std::vector<uint32_t> tri(std::initializer_list<uint32_t> i) {
  return i;
}

// The value of an 8-bit sRGB code in linear light (IEC 61966-2-1), computed apart from the reader.
float srgb8(int c) {
  const double v = c / 255.0;
  return float(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
}

const std::string kAsciiPly =
    "ply\n"
    "format ascii 1.0\n"
    "comment made by hand\n"
    "element material 1\n"
    "property float shininess\n"
    "property list uchar uchar name\n"
    "element vertex 5\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property float confidence\n"
    "property float nx\n"
    "property float ny\n"
    "property float nz\n"
    "property list uchar int unrelated\n"
    "property uchar red\n"
    "property uchar green\n"
    "property uchar blue\n"
    "element face 2\n"
    "property uchar flags\n"
    "property list uchar int vertex_indices\n"
    "property list uchar float texcoord\n"
    "element edge 1\n"
    "property int vertex1\n"
    "property int vertex2\n"
    "end_header\n"
    "0.5 3 1 2 3\n"
    "0 0 0 0.9 0 0 2 0 255 0 128\n"
    "1 0 0 0.9 0 0 1 2 7 7 0 255 0\n"
    "\n"  // blank lines between records are allowed
    "1 1 0 0.9 0 0 1 1 -1 10 20 30\r\n"
    "0 1 0 0.9 0 3 0 0 255 255 255\n"
    "9 9 9 0.9 1 0 0 0 0 0 0\n"
    "7 3 0 1 2 6 0 0 1 0 1 1\n"
    "0 4 0 2 3 4 0\n"
    "0 1\n";

TEST(MeshReader, AsciiPlyReadsKnownValuesAndSkipsTheRest) {
  MeshReadReport r;
  TriangleMesh m = readBytes("hand.ply", kAsciiPly, &r);
  ASSERT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.positions[2], glm::vec3(1, 1, 0));
  EXPECT_EQ(m.positions[4], glm::vec3(9, 9, 9));
  ASSERT_EQ(m.normals.size(), 5u);
  EXPECT_EQ(m.normals[0], glm::vec3(0, 0, 1));  // normalised from (0, 0, 2)
  EXPECT_EQ(m.normals[3], glm::vec3(0, 1, 0));
  ASSERT_EQ(m.colors.size(), 5u);
  EXPECT_FLOAT_EQ(m.colors[0].r, 1.0f);
  EXPECT_FLOAT_EQ(m.colors[0].g, 0.0f);
  EXPECT_FLOAT_EQ(m.colors[0].b, srgb8(128));  // 0.2158605
  EXPECT_FLOAT_EQ(m.colors[2].r, srgb8(10));   // the linear segment of the sRGB curve
  EXPECT_FLOAT_EQ(m.colors[2].b, srgb8(30));
  // The quad (0 2 3 4) fans out from its first corner.
  EXPECT_EQ(m.indices, tri({0, 1, 2, 0, 2, 3, 0, 3, 4}));
  EXPECT_EQ(r.facesRead, 2u);
  EXPECT_EQ(r.polygonsTriangulated, 1u);
  EXPECT_EQ(r.trianglesKept, 3u);
  EXPECT_EQ(r.degenerateDropped, 0u);
  EXPECT_EQ(r.nonFiniteVertices, 0u);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
}

// The same mesh in both binary byte orders: double positions, float normals and colours, a
// uint count and ushort indices, a scalar and a list to skip on each element, and the faces
// written before the vertices.
std::string binaryPly(bool big) {
  std::string s = std::string("ply\nformat ") +
                  (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\n"
                  "element face 2\n"
                  "property list uint ushort vertex_index\n"
                  "property int flags\n"
                  "property list uchar double extra\n"
                  "element vertex 6\n"
                  "property double x\n"
                  "property double y\n"
                  "property double z\n"
                  "property short skipme\n"
                  "property float nx\n"
                  "property float ny\n"
                  "property float nz\n"
                  "property float red\n"
                  "property float green\n"
                  "property float blue\n"
                  "end_header\n";
  // A pentagon and a triangle.
  put<uint32_t>(s, 5, big);
  for (uint16_t i : {0, 1, 2, 3, 4}) put<uint16_t>(s, i, big);
  put<int32_t>(s, -7, big);
  put<uint8_t>(s, 2, big);
  put<double>(s, 1.5, big), put<double>(s, 2.5, big);
  put<uint32_t>(s, 3, big);
  for (uint16_t i : {5, 4, 0}) put<uint16_t>(s, i, big);
  put<int32_t>(s, 0, big);
  put<uint8_t>(s, 0, big);
  const double xy[6][2] = {{0, 0}, {2, 0}, {3, 1}, {1, 3}, {-1, 1}, {-2, -2}};
  for (int v = 0; v < 6; ++v) {
    put<double>(s, xy[v][0], big), put<double>(s, xy[v][1], big), put<double>(s, 0.25 * v, big);
    put<int16_t>(s, -1, big);
    put<float>(s, 0, big), put<float>(s, 0, big), put<float>(s, 1, big);
    put<float>(s, 0.1f * v, big), put<float>(s, 0.5f, big), put<float>(s, 1.0f, big);
  }
  return s;
}

TEST(MeshReader, BinaryPlyOfBothByteOrdersReadsTheSameKnownValues) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    MeshReadReport r;
    TriangleMesh m = readBytes("bin.ply", binaryPly(big), &r);
    ASSERT_EQ(m.positions.size(), 6u);
    EXPECT_EQ(m.positions[2], glm::vec3(3, 1, 0.5f));
    EXPECT_EQ(m.positions[5], glm::vec3(-2, -2, 1.25f));
    ASSERT_EQ(m.normals.size(), 6u);
    EXPECT_EQ(m.normals[5], glm::vec3(0, 0, 1));
    ASSERT_EQ(m.colors.size(), 6u);
    EXPECT_FLOAT_EQ(m.colors[3].r, 0.3f);  // float colours are linear as given
    EXPECT_FLOAT_EQ(m.colors[3].g, 0.5f);
    // The pentagon's fan, then the triangle.
    EXPECT_EQ(m.indices, tri({0, 1, 2, 0, 2, 3, 0, 3, 4, 5, 4, 0}));
    EXPECT_EQ(r.facesRead, 2u);
    EXPECT_EQ(r.polygonsTriangulated, 1u);
    EXPECT_EQ(r.trianglesKept, 4u);
    EXPECT_TRUE(r.warnings.empty());
  }
}

TEST(MeshReader, ObjReadsAllCornerFormsNegativeIndicesAndFans) {
  const std::string obj =
      "# a comment\n"
      "mtllib scene.mtl\n"
      "o thing\n"
      "v 0 0 0\n"
      "v 1 0 0 1.0\n"          // a w is ignored
      "v 1 1 0 0.5 0.5 0.5\n"  // so are vertex colours
      "v 0 1 0\n"
      "vt 0 0\n"
      "vt 1 0\n"
      "g group\n"
      "usemtl red\n"
      "s off\n"
      "f 1 2 3 4\n"         // a quad: two triangles
      "f -4/1 -3/2 -2/2\n"  // relative indices: vertices 1 2 3
      "v 5 5 5\n"
      "f 5 -1/ 1 \\\n"  // a repeated vertex through a relative index, continued...
      "  2 # ...on the next line\n"
      "l 1 2\n"
      "p 3\n";
  MeshReadReport r;
  TriangleMesh m = readBytes("hand.obj", obj, &r);
  ASSERT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.positions[1], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.positions[4], glm::vec3(5, 5, 5));
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.colors.empty());
  // "f 5 -1/ 1 2" is 5 5 1 2: its fan (5 5 1) repeats a vertex and is dropped, (5 1 2) stays.
  EXPECT_EQ(m.indices, tri({0, 1, 2, 0, 2, 3, 0, 1, 2, 4, 0, 1}));
  EXPECT_EQ(r.facesRead, 3u);
  EXPECT_EQ(r.polygonsTriangulated, 2u);
  EXPECT_EQ(r.degenerateDropped, 1u);
  EXPECT_EQ(r.trianglesKept, 4u);
}

TEST(MeshReader, ObjSplitsVerticesWhoseCornersNameDifferentNormals) {
  // Two faces of a box meet at the edge 2-3 with different normals (a hard edge); the vertices
  // off that edge keep theirs; a corner that names normal 1 again shares the first copy.
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 1 1\nv 0 1 1\n"
      "vn 0 0 2\nvn 0 -1 0\n"
      "f 1//1 2//1 3//1 4//1\n"
      "f 4//2 3//2 5//2 6//2\n"
      "f 3//2 5//2 4//2\n";
  MeshReadReport r;
  TriangleMesh m = readBytes("box.obj", obj, &r);
  // Vertices 3 and 4 (0-based 2, 3) have a copy each with normal 2.
  ASSERT_EQ(m.positions.size(), 8u);
  ASSERT_EQ(m.normals.size(), 8u);
  EXPECT_EQ(m.positions[6], m.positions[3]);
  EXPECT_EQ(m.positions[7], m.positions[2]);
  for (int v : {0, 1, 2, 3}) EXPECT_EQ(m.normals[v], glm::vec3(0, 0, 1)) << v;
  for (int v : {4, 5, 6, 7}) EXPECT_EQ(m.normals[v], glm::vec3(0, -1, 0)) << v;
  EXPECT_EQ(m.indices, tri({0, 1, 2, 0, 2, 3, 6, 7, 4, 6, 4, 5, 7, 4, 6}));
  EXPECT_TRUE(r.warnings.empty());
}

TEST(MeshReader, ObjCornersWithoutNormalsGetTheirTrianglesNormalAndAWarning) {
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
      "vn 1 0 0\n"
      "f 1//1 3//1 4//1\n"  // in the x = 0 plane
      "f 1 2 3\n";          // in the z = 0 plane, no normals
  MeshReadReport r;
  TriangleMesh m = readBytes("mixed.obj", obj, &r);
  ASSERT_EQ(m.positions.size(), 6u);  // vertices 1 and 3 split: one with vn 1, one without
  EXPECT_EQ(m.normals[0], glm::vec3(1, 0, 0));
  EXPECT_EQ(m.normals[1], glm::vec3(0, 0, 1));  // computed from triangle (1 2 3)
  EXPECT_EQ(m.normals[4], glm::vec3(0, 0, 1));
  EXPECT_EQ(m.normals[5], glm::vec3(0, 0, 1));
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("3 face corners have no normal"), std::string::npos)
      << r.warnings[0];
}

// The "mesh with degenerate triangles" hard case: every kind is dropped and counted, none is
// rendered, the good ones stay in order.
TEST(MeshReader, DegenerateTrianglesAreDroppedAndCounted) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
      "property float z\nelement face 7\nproperty list uchar uint vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n2 0 0\nnan 0 0\n1e39 0 0\n"
      "3 0 1 2\n"     // good
      "3 0 0 2\n"     // repeated index
      "3 0 1 3\n"     // collinear: zero area
      "3 0 1 4\n"     // a NaN corner
      "3 0 2 5\n"     // a corner beyond float's range (infinite)
      "2 0 1\n"       // an edge, not a triangle
      "4 1 0 3 2\n";  // a quad whose first fan triangle is collinear: one kept, one dropped
  MeshReadReport r;
  TriangleMesh m = readBytes("degenerate.ply", ply, &r);
  EXPECT_EQ(m.positions.size(), 6u);  // all vertices stay; none of the bad ones is referenced
  EXPECT_EQ(m.indices, tri({0, 1, 2, 1, 3, 2}));
  EXPECT_EQ(r.facesRead, 7u);
  EXPECT_EQ(r.trianglesKept, 2u);
  EXPECT_EQ(r.degenerateDropped, 6u);
  EXPECT_EQ(r.nonFiniteVertices, 2u);
  EXPECT_EQ(r.polygonsTriangulated, 1u);

  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 0 0 inf\n"
      "f 1 2 3\nf 1 1 3\nf 1 2 4\nf 1 2 5\nf 1 2\nf 3\n";
  MeshReadReport o;
  m = readBytes("degenerate.obj", obj, &o);
  EXPECT_EQ(m.indices, tri({0, 1, 2}));
  EXPECT_EQ(o.facesRead, 6u);
  EXPECT_EQ(o.degenerateDropped, 5u);
  EXPECT_EQ(o.nonFiniteVertices, 1u);

  // All faces degenerate: an empty mesh, not an error.
  m = readBytes("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", &o);
  EXPECT_EQ(m.triangles(), 0u);
  EXPECT_EQ(o.degenerateDropped, 1u);
}

TEST(MeshReader, UnusableNormalsAndOddColoursAreWarnedAbout) {
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property int red\nproperty int green\nproperty int blue\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0 0 1 2 3\n1 0 0 nan 0 1 1 2 3\n0 1 0 0 0 1 1 2 3\n3 0 1 2\n";
  MeshReadReport r;
  TriangleMesh m = readBytes("odd.ply", ply, &r);
  EXPECT_TRUE(m.colors.empty());
  EXPECT_EQ(m.normals[0], glm::vec3(0));
  EXPECT_EQ(m.normals[1], glm::vec3(0));
  ASSERT_EQ(r.warnings.size(), 2u);
  EXPECT_NE(r.warnings[0].find("colours ignored"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[1].find("2 vertex normals"), std::string::npos) << r.warnings[1];
}

TEST(MeshReader, ColourTypes) {
  // ushort codes are sRGB like uchar ones; float values are linear, clamped into [0,1].
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nproperty ushort red\nproperty float green\nproperty double blue\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 65535 1.5 0.25\n1 0 0 0 -2 nan\n0 1 0 32896 0.5 1\n3 0 1 2\n";
  MeshReadReport r;
  TriangleMesh m = readBytes("colours.ply", ply, &r);
  ASSERT_EQ(m.colors.size(), 3u);
  EXPECT_EQ(m.colors[0], Rgb(1, 1, 0.25f));
  EXPECT_EQ(m.colors[1], Rgb(0, 0, 0));
  EXPECT_FLOAT_EQ(m.colors[2].r, srgb8(128));  // 32896 = 128 * 257
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("3 colour values outside [0, 1] were clamped"), std::string::npos)
      << r.warnings[0];
}

struct BadCase {
  const char* what;
  std::string name, bytes;
  std::string position;  // exactly as Error::position() must give it
  const char* reason;    // a part of Error::reason()
};

std::string plyHeader(const std::string& format, const std::string& vertexCount,
                      const std::string& faceCount, const std::string& indexType = "int") {
  return "ply\nformat " + format + " 1.0\nelement vertex " + vertexCount +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + faceCount +
         "\nproperty list uchar " + indexType + " vertex_indices\nend_header\n";
}

std::string littleTriangle(int indexA = 0) {
  std::string s = plyHeader("binary_little_endian", "3", "1");
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put<float>(s, f, false);
  put<uint8_t>(s, 3, false);
  for (int i : {indexA, 1, 2}) put<int32_t>(s, i, false);
  return s;
}

TEST(MeshReader, MalformedFilesNameTheFileAndThePosition) {
  const std::string ascii3 = plyHeader("ascii", "3", "1");  // 9 header lines
  const std::string bin = littleTriangle();
  const size_t binHeader = plyHeader("binary_little_endian", "3", "1").size();
  const size_t binFaces = binHeader + 36;  // three vertices of 12 bytes
  std::vector<BadCase> cases = {
      {"empty PLY", "e.ply", "", "byte 0", "empty file"},
      {"empty OBJ", "e.obj", "", "byte 0", "empty file"},
      {"OBJ without faces", "v.obj", "v 1 2 3\n# nothing else\n", "line 2", "no faces"},
      {"not a PLY", "n.ply", "solid cube\n", "byte 0", "not a PLY file"},
      {"PLY without faces", "p.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n1 2 3\n",
       "line 7", "no 'face' element"},
      {"PLY with no face records", "p0.ply", plyHeader("ascii", "3", "0") + "0 0 0\n1 0 0\n0 1 0\n",
       "line 7", "holds no faces"},
      {"face list of floats", "fl.ply", plyHeader("ascii", "3", "1", "float"), "line 7",
       "indices must be integers"},
      {"no x", "nx.ply",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\n"
       "element face 0\nproperty list uchar int vertex_indices\nend_header\n",
       "line 3", "no scalar property 'x'"},
      {"ascii truncated in the vertices", "t.ply", ascii3 + "0 0 0\n1 0 0\n", "line 11",
       "ends inside element 'vertex': 2 of the 3"},
      {"ascii truncated in a line", "tl.ply", ascii3 + "0 0 0\n1 0 0\n0 1\n", "line 12",
       "ends before the last property 'z'"},
      {"ascii truncated in the faces", "tf.ply", ascii3 + "0 0 0\n1 0 0\n0 1 0\n", "line 12",
       "ends inside element 'face': 0 of the 1"},
      {"ascii face list shorter than its count", "fs.ply",
       ascii3 + "0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "line 13", "ends before the last property"},
      {"ascii vertex count of 2^40", "big.ply",
       plyHeader("ascii", "1099511627776", "1") + "0 0 0\n", "line 3", "at most 2^32 - 1"},
      {"ascii vertex count of 2^31", "lie.ply", plyHeader("ascii", "2147483648", "1") + "0 0 0\n",
       "line 10", "ends inside element 'vertex': 1 of the 2147483648"},
      {"ascii face count of 10^9", "lief.ply",
       plyHeader("ascii", "3", "1000000000") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "line 13",
       "1 of the 1000000000"},
      {"ascii index out of range", "r.ply", ascii3 + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 13",
       "vertex index 3 is out of range"},
      {"ascii negative index", "neg.ply", ascii3 + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "line 13",
       "as a vertex index"},
      {"ascii bad number", "bad.ply", ascii3 + "0 0 0\n1 0x 0\n0 1 0\n3 0 1 2\n", "line 11",
       "cannot read '0x' as float (property 'y')"},
      {"ascii extra values", "x.ply", ascii3 + "0 0 0 7\n", "line 10", "more values"},
      {"binary vertex count of 2^31", "bl.ply",
       plyHeader("binary_little_endian", "2147483648", "1") + std::string(64, '\0'),
       "byte " + std::to_string(plyHeader("binary_little_endian", "2147483648", "1").size()),
       "declares 2147483648 'vertex' records"},
      {"binary truncated in the faces", "bt.ply", bin.substr(0, bin.size() - 2),
       "byte " + std::to_string(binFaces + 1), "ends inside element 'face'"},
      {"binary index out of range", "br.ply", littleTriangle(3),
       "byte " + std::to_string(binFaces + 1), "vertex index 3 is out of range"},
      {"binary negative index", "bn.ply", littleTriangle(-5),
       "byte " + std::to_string(binFaces + 1), "negative vertex index"},
      {"OBJ index out of range", "r.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4",
       "vertex index 4 is out of range"},
      {"OBJ forward reference", "fw.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", "line 3",
       "out of range"},
      {"OBJ relative index too far back", "rel.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
       "line 4", "index -4 is out of range"},
      {"OBJ index 0", "z.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4", "index 0"},
      {"OBJ normal out of range", "n.obj",
       "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", "line 5",
       "normal index 2 is out of range"},
      {"OBJ texture coordinate out of range", "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n",
       "line 4", "texture coordinate index 1 is out of range"},
      {"OBJ bad number", "b.obj", "v 0 0 0\nv 1 abc 0\n", "line 2", "cannot read 'abc'"},
      {"OBJ short vertex", "s.obj", "v 0 0\n", "line 1", "three numbers"},
      {"OBJ bad corner", "c.obj", "v 0 0 0\nf 1/2/3/4 1 1\n", "line 2", "more than three parts"},
      {"OBJ corner without vertex", "cv.obj", "v 0 0 0\nf //1 1 1\n", "line 2", "no vertex index"},
      {"unknown extension", "mesh.stl", "solid\n", "", "unknown mesh format '.stl'"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    const Error e = errorOf(c.name, c.bytes);
    EXPECT_EQ(e.file(), c.name);
    EXPECT_EQ(e.position(), c.position) << e.what();
    EXPECT_NE(e.reason().find(c.reason), std::string::npos) << e.what();
  }
}

// Every prefix of a valid file is either read or rejected with an Error: never a crash, and
// never a mesh with indices out of range.
TEST(MeshReader, EveryTruncationOfValidFilesFailsCleanly) {
  std::vector<std::pair<std::string, std::string>> files = {
      {"a.ply", kAsciiPly},
      {"l.ply", binaryPly(false)},
      {"b.ply", binaryPly(true)},
      {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf -1 -2 -3\n"}};
  for (const auto& [name, bytes] : files)
    for (size_t n = 0; n <= bytes.size(); ++n) {
      try {
        TriangleMesh m = readBytes(name, bytes.substr(0, n));
        for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size()) << name << " " << n;
      } catch (const Error& e) {
        ASSERT_EQ(e.file(), name);
      }
    }
}

TEST(MeshReader, ReadsFromAFileByExtensionAndNamesAMissingOne) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("nestlight_mesh_test_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "Hand.PLY").string();
  std::ofstream(path, std::ios::binary) << kAsciiPly;
  TriangleMesh a = readMesh(path), b = readBytes("x.ply", kAsciiPly);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.indices, b.indices);
  std::filesystem::remove_all(dir);
  try {
    readMesh(path);
    ADD_FAILURE() << "a missing file was read";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.reason().find("cannot open"), std::string::npos);
  }
}

std::string meshFile(const char* name) {
  const std::string p = (::nestlight::test::sharedData() / "meshes" / name).string();
  return std::filesystem::exists(p) ? p : std::string();
}

TEST(MeshReader, RealBunnyAsciiPly) {
  const std::string path = meshFile("bunny.ply");
  if (path.empty())
    GTEST_SKIP() << "no bunny.ply under " << ::nestlight::test::sharedData().string() << "/meshes";
  MeshReadReport r;
  TriangleMesh m = readMesh(path, &r);
  EXPECT_EQ(m.positions.size(), 35947u);
  EXPECT_EQ(r.facesRead, 69451u);
  EXPECT_EQ(r.trianglesKept, 69451u);
  EXPECT_EQ(m.triangles(), 69451u);
  EXPECT_EQ(r.degenerateDropped, 0u);
  EXPECT_EQ(r.polygonsTriangulated, 0u);
  EXPECT_TRUE(m.normals.empty());
  EXPECT_TRUE(m.colors.empty());
  EXPECT_EQ(m.positions[0], glm::vec3(-0.0378297f, 0.12794f, 0.00447467f));  // the first line
  for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
}

TEST(MeshReader, RealGargoyleBinaryPlyWithNormalsAndColours) {
  const std::string path = meshFile("gargoyle.ply");
  if (path.empty())
    GTEST_SKIP() << "no gargoyle.ply under " << ::nestlight::test::sharedData().string()
                 << "/meshes";
  MeshReadReport r;
  TriangleMesh m = readMesh(path, &r);
  EXPECT_EQ(m.positions.size(), 25002u);
  EXPECT_EQ(r.facesRead, 50000u);
  EXPECT_EQ(r.trianglesKept + r.degenerateDropped, 50000u);
  EXPECT_EQ(r.degenerateDropped, 0u);
  ASSERT_EQ(m.normals.size(), 25002u);
  ASSERT_EQ(m.colors.size(), 25002u);
  EXPECT_TRUE(r.warnings.empty());
  for (const auto& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-6f);
  for (const auto& c : m.colors)
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(c[k] >= 0 && c[k] <= 1);
}

}  // namespace
