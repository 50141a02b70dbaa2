// `diffrender`: inserted meshes that belong in the scan, by differential rendering after Rohmer,
// Jendersie and Grosch, "Natural Environment Illumination: Coherent Interactive Augmented Reality
// for Mobile and non-Mobile Devices" (IEEE TVCG 2017), sections 5 to 7. The scan's captured
// radiance holds all the light of the place: an inserted mesh is lit from it (a distance impostor
// of the scene rendered at the meshes' centre, queried by direction or traced), and what the mesh
// changes on the scan (its shadow, its bounce) is dL = L_with - L_without, added to the capture.
// docs/DIFFRENDER.md gives the parameters and the deviations.
#pragma once

#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct DiffrenderParameters {
  // How a ray or cone finds the scene's radiance: the environment map's lookup by direction
  // alone (em), distance impostor tracing (dit, Szirmay-Kalos et al. 2005), voxel cones (vct) or
  // exact rays (exact).
  enum class Query { Em, Dit, Vct, Exact } query = Query::Dit;
  enum class Quality { Low, Med, High } quality = Quality::Med;
  int samples = 16;        // N: cosine directions per scan pixel (material and dL)
  int objectSamples = 16;  // BRDF samples per object pixel
  int cache = 8;           // |H_a|: box hits traced per scan pixel (eq. 9)
  glm::ivec3 objectVoxels{32};
  bool selfShadow = true;
  bool secondaryBounce = false;
  int impostorSize = 256;        // texels of a distance impostor's face
  int sceneVoxels = 256;         // vct's scene volume
  int deltaScale = 2;            // dL at 1 / delta_scale of the image's resolution
  float ambient = 0;             // radiance of a self-shadowed object ray
  float rhoMax = 1;              // the material estimate's clamp
  bool materialEstimate = true;  // false: the recorded colour as rho (an ablation)
  int ditIterations = 8;         // DIT's secant steps after its search
  // Each material ray also traced by `exact`, the query's hits counted against it (stats
  // compared and within_footprint): how far an approximation's hits stray, at exact's cost.
  bool compareExact = false;
  // Where the distance impostor is drawn from, in the scene's coordinates; none: the middle of
  // the inserted meshes' boxes.
  std::optional<glm::dvec3> impostorCentre;
  // A folder (relative to the scene file) for each still's images beside the composite:
  // diffrender_delta.exr (dL on the scan), diffrender_rho.exr (the material estimate), both at
  // 1 / delta_scale, and diffrender_mask.exr (1 scan, 2 inserted mesh, 0 else). Empty: none.
  std::string aovs;
  // The colour layer holding the scan's captured radiance (`nestlight bake-radiance` writes one),
  // whatever gi.mode says; empty: the scan's own colour in the radiance-cache mode.
  std::string capture;
  // A photograph of the camera's view (linear .exr/.hdr, or a .png of display values decoded with
  // gamma 2.2 as colour-match does) that stands for the capture on the scan's pixels and behind
  // the scene, brought into the scan's colour space by `backgroundMap` (colour-match's C, rows)
  // and the composite back into the photograph's by its inverse. Empty: the capture.
  std::string background;
  glm::mat3 backgroundMap{1.0f};
};

const ParameterSpecs& diffrenderParameterSpecs();
MethodInfo diffrenderMethodInfo();
// From scene.gi.parameters with the quality preset's values for the keys not given; throws
// nestlight::Error naming scene.gi.parameters.<key>.
DiffrenderParameters diffrenderParameters(const Scene& scene);
// The scene as the frame draws it: with `capture`, every scan's colour is that layer, its
// radiance, in the radiance-cache mode. Throws nestlight::Error naming
// scene.gi.parameters.capture when a scan lacks the layer, or scene.gi.mode in the albedo mode
// without a capture.
Scene diffrenderCaptureScene(const Scene& scene, const DiffrenderParameters& p);
const char* queryName(DiffrenderParameters::Query q);
const char* qualityName(DiffrenderParameters::Quality q);

std::unique_ptr<Method> createDiffrenderMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
