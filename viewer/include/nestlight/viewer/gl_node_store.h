// Resident nodes as GL buffers. Loader threads convert a node's points into the GPU format;
// the render thread only copies bytes into a buffer.
//
// GPU point format, 20 bytes: position as 3 floats relative to the node's cube origin (world
// units: small numbers, so no precision is lost at national-grid offsets), the display colour
// as RGBA8, and the normal octahedron-encoded in 2 x 16 bits (0 when the scan has none).
#pragma once

#include <epoxy/gl.h>

#include <string>
#include <unordered_map>
#include <vector>

#include "nestlight/octree/metadata.h"
#include "nestlight/streaming/node_store.h"

namespace nestlight::viewer {

inline constexpr size_t kGpuPointBytes = 20;

enum class ColourMode { Rgb, Intensity, Classification, Elevation, Normal };
const char* colourModeName(ColourMode m);
// Parses "rgb", "intensity", "classification", "elevation", "normal"; throws on others.
ColourMode parseColourMode(const std::string& name);
// The modes this scan can show (elevation always; the rest when it has the attribute).
std::vector<ColourMode> availableColourModes(const Metadata& meta);

class GlNodeStore : public streaming::NodeStore {
 public:
  GlNodeStore(const Metadata& meta, ColourMode mode);
  ~GlNodeStore() override;

  void prepare(const NodeKey& key, PointBuffer&& points, streaming::PreparedNode& out) const override;
  uint64_t upload(const streaming::PreparedNode& node) override;
  void release(uint64_t handle) override;

  // Nodes prepared with another mode still upload; the streamer is flushed when it changes.
  void setColourMode(ColourMode m) { mode_ = m; }
  ColourMode colourMode() const { return mode_; }
  GLuint buffer(uint64_t handle) const { return static_cast<GLuint>(handle); }
  uint64_t liveBuffers() const { return live_.size(); }

 private:
  const Metadata& meta_;
  ColourMode mode_;
  int rgb_ = -1, normal_ = -1, intensity_ = -1, classification_ = -1;
  std::unordered_map<uint64_t, size_t> live_;
};

}  // namespace nestlight::viewer
