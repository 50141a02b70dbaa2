// `projection`: final gathering by importance-driven point projection (Maletz, Wang and Bowers,
// "Importance-Driven Point Projection for GPU-based Final Gathering", 2011) on the raster frame:
// the lights' cut thinned to a point set S (every point's area from its neighbours' spacing),
// split into equal-count clusters (clusters.h), and per receiver pixel a few random points per
// cluster give the clusters' importance, which shares the importance samples among them
// (projection_allocate.glsl); every sample is splatted into the receiver's hemi-octahedral
// micro-buffer (hemi_octahedral.h) with the solid angle it stands for, and the micro-buffer's
// light through the receiver's BSDF is its indirect light. docs/PROJECTION.md describes the
// parameters and what is built.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct ProjectionParameters {
  int points = 262144;        // |S|: the lights' cut thinned to at most this many points
  int clusters = 512;         // K, a power of two
  int randomPerCluster = 2;   // N_rnd: random points per cluster (importance and splats)
  int samplesPerCluster = 4;  // N_s / K: importance samples per cluster, on average
  int microBuffer = 32;       // M: texels per side of the hemi-octahedral micro-buffer
  // importance (the paper), random (every sample uniform over S: the paper's baseline), brute
  // (all of S, each point its own area: the micro-buffer's reference).
  enum class Sampling { Importance, Random, Brute } sampling = Sampling::Importance;
  int splat = 0;       // 0: adaptive (eq. 3), else a fixed square of 1, 2 or 3 texels per side
  int fillPasses = 2;  // passes closing holes between splats (0: the paper's micro-buffers)
  // Image-space adaptive sampling (section 3.3): gather the grid (step `grid`), then per finer
  // level the pixels whose coherence metric over their cell's corners reaches epsilon (times
  // epsilonLevelFactor per level below the first), the others upsampled from the corners.
  bool adaptive = true;
  int grid = 4;
  float lambda = 8.0f;
  float epsilon = 0.3f;
  float epsilonLevelFactor = 2.0f;
  // The levels gathered (0: all): with N, the levels below the first N only interpolate, which is
  // what the progressive view shows as each level completes (the paper's Fig. 11).
  int levels = 0;
  // Interactive frames (the viewer): the grid is gathered whole, the finer levels' pixels for at
  // most this long a frame; while the view does not change each frame goes on where the last one
  // stopped, until the image is the still's (the paper's progressive rendering). 0: every frame
  // gathers all its levels.
  double progressiveMs = 33;
  // The post filter's window: -1 auto (7 x 7, 3 x 3 where glossy), 0 none, 3 or 7.
  int postFilter = -1;
  // The albedo mode's bounces beyond the gathered one (gi.max_bounces 3 and more) gather at this
  // many points of S, every other point taking its light from the nearest of its cluster's.
  int bounceReceivers = 4096;
  // Glossy meshes' surfels keep a glossy lobe for each of the 4 lights that light them most (the
  // light's direction and irradiance) and send each receiver what those lobes reflect toward it;
  // the importance of a glossy source grows with it (paper section 3.2, glossy-to-glossy). False:
  // every point reflects diffusely, a glossy surfel with its material's directional albedo.
  bool glossyToGlossy = true;
  // Stills at this many subpixels a side, box-filtered (the paper's 2xAA: 2).
  int supersample = 1;
  // Pixels (x, y; top row 0) whose micro-buffers each still writes to dumpFolder as EXR.
  std::vector<std::array<int, 2>> dumpPixels;
  std::string dumpFolder;
};

const ParameterSpecs& projectionParameterSpecs();
MethodInfo projectionMethodInfo();
// From scene.gi.parameters; throws nestlight::Error naming scene.gi.parameters.<key>.
ProjectionParameters projectionParameters(const Scene& scene);

// The file a dumped micro-buffer of image pixel (x, y) is written to in dump_folder.
std::string microBufferFileName(int x, int y);

std::unique_ptr<Method> createProjectionMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
