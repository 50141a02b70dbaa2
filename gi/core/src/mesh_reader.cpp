// Mesh files in, TriangleMesh out: the format by extension (PLY, Turk 1994; Wavefront OBJ), then
// the shared cleaning of mesh_builder. Inserted objects are meshes of thousands to millions of
// triangles, small beside a scan, so a file is read whole into memory.
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "mesh_builder.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

TriangleMesh readMeshFromMemory(const std::string& name, const void* data, size_t size,
                                MeshReadReport* report) {
  std::string ext;
  if (const size_t dot = name.find_last_of('.');
      dot != std::string::npos && name.find_first_of("/\\", dot) == std::string::npos)
    ext = name.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  meshio::MeshBuilder b;
  const auto* bytes = static_cast<const uint8_t*>(data);
  if (ext == "ply")
    meshio::readPly(name, bytes, size, b);
  else if (ext == "obj")
    meshio::readObj(name, bytes, size, b);
  else
    throw Error(name, "", "unknown mesh format '." + ext + "': expected .ply or .obj");
  b.finish();
  if (report) *report = std::move(b.report);
  return std::move(b.mesh);
}

TriangleMesh readMesh(const std::string& path, MeshReadReport* report) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
  std::string bytes;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f.get())) > 0) bytes.append(buf, n);
  if (std::ferror(f.get()))
    throw Error(path, Error::atByte(bytes.size()),
                std::string("read error: ") + std::strerror(errno));
  return readMeshFromMemory(path, bytes.data(), bytes.size(), report);
}

}  // namespace nestlight::gi
