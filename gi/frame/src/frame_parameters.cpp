// The GI frame's parameters (nestlight/gi/frame/frame_parameters.h): every method on the frame
// reads them too.
#include "nestlight/gi/frame/frame_parameters.h"

namespace nestlight::gi {

const ParameterSpecs& rasterParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::integer("shadow_map_size", 16, 16384, 2048, "texels per side of each shadow-map layer"),
      P::choice("rasteriser", {"points", "compute"}, "points",
                "the scans' G-buffer: points (GL_POINTS splats sized by the measured spacing) or "
                "compute (one pixel per point, the points within 1% of the nearest depth "
                "averaged); shadow maps always take splats"),
      P::choice("splatting", {"hqs", "basic"}, "hqs",
                "points rasteriser: hqs (the kernel-weighted mean of the splats near the front "
                "surface, Botsch et al. 2005) or basic (the nearest splat wins)"),
      P::number("splat_scale", 0.1, 16, 2.25, "splat diameter in measured point spacings"),
      P::number("point_budget", 1, 1e10, 5'000'000, "points of each scan's resident cut"),
      P::number("gpu_budget_mb", 1, 1 << 20, 1024, "resident MiB of each scan"),
      // Larger tiles would pass GL's viewport limit with the splats' guard band, and a tile's
      // read-back its 2 GiB limit.
      P::integer("max_tile", 16, 8192, 2048, "larger images render in tiles of this many pixels"),
      P::number("stream_timeout", 0.1, 1e6, 300,
                "seconds to wait for a view's cut to load completely"),
  };
  return specs;
}

FrameParameters parseFrameParameters(const Scene& scene,
                                     const std::vector<std::string>& otherKeys) {
  std::vector<std::string> names = parameterNames(rasterParameterSpecs());
  names.insert(names.end(), otherKeys.begin(), otherKeys.end());
  checkParameterNames(scene, names);
  const ResolvedParameters r = resolveParameterValues(scene, rasterParameterSpecs());
  FrameParameters p;
  p.shadowMapSize = int(r.integer("shadow_map_size"));
  p.computeRasteriser = r.string("rasteriser") == "compute";
  p.hqs = r.string("splatting") == "hqs";
  p.splatScale = float(r.number("splat_scale"));
  p.pointBudget = uint64_t(r.number("point_budget"));
  p.gpuBytes = uint64_t(r.number("gpu_budget_mb")) << 20;
  p.maxTile = int(r.integer("max_tile"));
  p.streamTimeoutSeconds = r.number("stream_timeout");
  return p;
}

}  // namespace nestlight::gi
