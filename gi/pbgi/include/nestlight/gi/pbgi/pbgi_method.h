// `pbgi`: point-based global illumination on a bounding-sphere hierarchy of the resident cut
// (Sabbadin et al., "High Dynamic Range Point Clouds for Real-Time Relighting", 2019, section 5),
// on the raster frame: each streamed node carries its own hierarchy (bsh_layer.h, built on the
// loader threads), a top tree over the lights' cut joins them (bsh.h, rebuilt when the cut
// changes), and receivers gather the scan's radiance through micro-buffers (micro_buffer.h).
// docs/SCENE.md describes the parameters.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct PbgiParameters {
  // The traversal: "classic" (per receiver, depth first), "mip" (pairs of nodes and receiver
  // blocks refined in parallel down to m-pixel-sized nodes), "x" (pairs while nodes exceed 32
  // m-pixel solid angles, then classic per receiver: the paper's X-PBGI).
  enum class Variant { Classic, Mip, X } variant = Variant::X;
  int pairCapacity =
      1 << 21;           // pairs per pair buffer, and entries of the receivers' lists (MIP, X)
  int microBuffer = 16;  // M: m-pixels per side of a micro-buffer ("micro_buffer", 4 to 64)
  bool conservative =
      false;  // refine only above 4 m-pixel solid angles (the paper's option against holes)
  // What an m-pixel nothing covered holds: "average" (the paper: the cloud's average colour, for
  // holes), "environment" (its radiance in that direction: what no point covers is sky; the
  // gather then owns the environment's light on receivers), "black" (measures coverage), or
  // "auto": environment when the scene has one, else average.
  enum class Empty { Auto, Average, Environment, Black } empty = Empty::Auto;
  bool prune = true;  // prune the scan's hierarchies at the paper's thresholds (meshes' never)
  // Inserted meshes' surfels as hierarchies of their own (mesh_trees.h): they occlude, reflect
  // the lights and emit; false: meshes only receive (the paper's setting).
  bool meshes = true;
  // The albedo mode's bounces beyond the first gather at hierarchy nodes standing for at most this
  // many points (every leaf below takes what its node gathered), not at every point.
  int bouncePoints = 256;
  // Traversal steps one dispatch takes per receiver before it yields (0: as many as the device
  // allows: on llvmpipe what its 65,535-iteration loop limit leaves, elsewhere 2^20). The
  // traversal resumes where it stopped, so the image does not depend on it.
  int stepsPerDispatch = 0;
};

// The gi.parameters pbgi reads beside raster's (src/pbgi_parameters.cpp), and its entry in the
// registry.
const ParameterSpecs& pbgiParameterSpecs();
MethodInfo pbgiMethodInfo();
// From scene.gi.parameters; throws nestlight::Error naming scene.gi.parameters.<key>.
PbgiParameters pbgiParameters(const Scene& scene);

std::unique_ptr<Method> createPbgiMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
