// Resident nodes as GL buffers. Loader threads convert a node's points into the GPU format and
// build its layers; the render thread only copies bytes into buffers.
//
// GPU point format, NL_POINT_WORDS (5) words (shaders/interface/frame_interface.glsl): position
// as 3 floats relative to the node's cube origin (world units: small numbers, so no precision is
// lost at national-grid offsets), the colour word, and the normal octahedron-encoded in 2 x 16
// bits (0 when the scan has none). The colour word is the display colour as sRGB RGBA8, or in
// ColourMode::Hdr a colour layer's linear colour as RGB9E5 (shaders/common/colour_word.glsl
// decodes both; programs set its uHdrColour from hdrColour()).
//
// Node layers: a GI method registers a NodeLayer (a hierarchy over the node's points, an HDR
// colour) and every node prepared from then on carries it as a buffer of its own, built on the
// loader thread, counted in the node's resident bytes and freed with the node.
#pragma once

#include <epoxy/gl.h>

#include <glm/glm.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "nestlight/frame/interface.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/streaming/node_store.h"

namespace nestlight::frame {

// Per-node data beside the points. prepare() runs on loader threads (it must be thread-safe)
// with the node's decoded points and their GPU form (kGpuPointBytes each).
class NodeLayer {
 public:
  virtual ~NodeLayer() = default;
  virtual std::string name() const = 0;
  virtual void prepare(const NodeKey& key, const PointBuffer& points,
                       const std::vector<uint8_t>& gpuPoints, std::vector<uint8_t>& out) const = 0;
};

// A unit normal in the GPU point format's word (octahedral, 2 x 16 bits; 0 for a zero or
// non-finite vector), as shaders/common/octahedral.glsl decodes it.
uint32_t packNormal(float x, float y, float z);
// Its inverse, as decodeNormal in shaders/common/octahedral.glsl: (0, 0, 0) for the word 0.
glm::vec3 unpackNormal(uint32_t word);

// Hdr: the octree's colour layer "hdr" (or another given to the store), linear HDR.
enum class ColourMode { Rgb, Intensity, Classification, Elevation, Normal, Hdr };
const char* colourModeName(ColourMode m);
// The elevation colouring's ramp (dark blue - teal - yellow, perceptually ordered) at t in [0, 1]
// (the scan's lowest to highest point), RGBA8 as the colour word holds it: for legends too.
uint32_t elevationRamp(double t);
// The intensity colouring: grey sqrt(intensity / 65535), since most returns are dark.
double intensityGrey(double intensity);
// Parses "rgb", "intensity", "classification", "elevation", "normal", "hdr"; throws on others.
ColourMode parseColourMode(const std::string& name);
// The modes this scan can show (elevation always; the rest when it has the attribute, hdr when
// it has the colour layer `hdrLayer`).
inline constexpr const char* kHdrLayerName =
    "hdr";  // the layer ColourMode::Hdr reads unless told otherwise
std::vector<ColourMode> availableColourModes(const Metadata& meta,
                                             const std::string& hdrLayer = kHdrLayerName);

class GlNodeStore : public streaming::NodeStore {
 public:
  // `layer`: what ColourMode::Hdr draws (required for it).
  GlNodeStore(const Metadata& meta, ColourMode mode,
              std::shared_ptr<const ColourLayerReader> layer = nullptr);
  ~GlNodeStore() override;
  GlNodeStore(const GlNodeStore&) = delete;
  GlNodeStore& operator=(const GlNodeStore&) = delete;

  void prepare(const NodeKey& key, PointBuffer&& points,
               streaming::PreparedNode& out) const override;
  uint64_t upload(const streaming::PreparedNode& node) override;
  void release(uint64_t handle) override;

  // Nodes prepared with another mode still upload; the streamer is flushed when it changes.
  // ColourMode::Hdr needs the store made with a colour layer.
  void setColourMode(ColourMode m);
  ColourMode colourMode() const { return mode_; }
  // Whether colour words are RGB9E5 (the shaders' uHdrColour).
  bool hdrColour() const { return mode_ == ColourMode::Hdr; }
  // The node's points buffer.
  GLuint buffer(uint64_t handle) const { return layerBuffer(handle, 0); }
  // Layer 0 is the points, 1.. the registered layers in order; 0 when the node was prepared
  // before that layer was added.
  GLuint layerBuffer(uint64_t handle, size_t layer) const;
  size_t layerBytes(uint64_t handle, size_t layer) const;

  // Adds a layer to nodes prepared from now on (flush the streamer to rebuild resident ones).
  // Returns its index (1, 2, ...). At most NL_MAX_NODE_LAYERS - 1 layers.
  size_t addLayer(std::shared_ptr<const NodeLayer> layer);
  size_t layerCount() const;

  uint64_t liveNodes() const { return live_.size(); }
  uint64_t liveBuffers() const;  // GL buffers held, points and layers
  uint64_t liveBytes() const;    // their bytes, as the streamer counts them

 private:
  struct Resident {
    std::vector<gl::Buffer> buffers;  // points, then layers
    std::vector<size_t> bytes;
  };
  const Metadata& meta_;
  ColourMode mode_;
  std::shared_ptr<const ColourLayerReader> colourLayer_;
  int rgb_ = -1, normal_ = -1, intensity_ = -1, classification_ = -1;
  mutable std::mutex layersMutex_;  // loader threads read the list while the render thread adds
  std::vector<std::shared_ptr<const NodeLayer>> layers_;
  std::unordered_map<uint64_t, Resident> live_;
  uint64_t nextHandle_ = 1;
};

}  // namespace nestlight::frame
