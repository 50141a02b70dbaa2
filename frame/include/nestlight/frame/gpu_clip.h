// Clipping volumes on the GPU: a ClipSet encoded into the ClipBlock uniform block
// (shaders/interface/frame_interface.glsl) relative to the origin of the frame the shaders'
// positions are in, so that the subtraction of large world coordinates happens once, in double,
// here. shaders/common/clip_volumes.glsl tests points against it; nodes whose cube the set keeps
// whole skip the test, and nodes it removes whole are not drawn (nodeOverlap).
#pragma once

#include "nestlight/frame/interface.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/clip_volume.h"

namespace nestlight::frame {

// Throws nestlight::Error when the set holds more volumes or polygon vertices than the block
// (NL_MAX_CLIP_VOLUMES, NL_MAX_CLIP_VERTICES): the viewer cannot show what it would clip.
ClipBlock encodeClipBlock(const ClipSet& set, const Vec3d& frameOrigin);

class GpuClip {
 public:
  // Uploads the encoded set (the buffer is made on first use, with a context current) and binds it
  // at NL_UBO_CLIP. An empty set uploads nothing: shaders skip the test by uClipTest.
  void bind(const ClipSet& set, const Vec3d& frameOrigin);

 private:
  gl::Buffer ubo_;
};

}  // namespace nestlight::frame
