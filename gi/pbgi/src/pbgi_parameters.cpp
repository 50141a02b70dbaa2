// `pbgi`'s declaration: its parameters and its entry in the registry.
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/pbgi/pbgi_method.h"

namespace nestlight::gi {

const ParameterSpecs& pbgiParameterSpecs() {
  using P = ParameterSpec;
  static const ParameterSpecs specs = {
      P::choice("variant", {"classic", "mip", "x"}, "x",
                "its traversal, x (X-PBGI, default), mip (MIP-PBGI) or classic")
          .asFlag(),
      P::integer("micro_buffer", 4, 64, 16, "m-pixels per side of a micro-buffer"),
      P::boolean("conservative", false,
                 "refine only above 4 m-pixel solid angles (the paper's option against holes)"),
      P::choice("empty", {"auto", "average", "environment", "black"}, "auto",
                "what an m-pixel nothing covered holds: average (the cloud's average colour), "
                "environment (its radiance in that direction), black, or auto (environment when "
                "the scene has one, else average)"),
      P::boolean("prune", true,
                 "prune the scan's hierarchies at the paper's thresholds (meshes' never)"),
      P::boolean("meshes", true,
                 "inserted meshes' surfels as hierarchies of their own (false: meshes only "
                 "receive)"),
      P::integer("bounce_points", 1, 1 << 24, 256,
                 "albedo mode: bounces beyond the first gather at nodes of at most this many "
                 "points"),
      P::integer("pair_capacity", 1, 1 << 23, 1 << 21,
                 "pairs per pair buffer, and entries of the receivers' lists (mip, x)"),
      P::integer("steps_per_dispatch", 1, 1 << 24, nullptr,
                 "traversal steps one dispatch takes per receiver before it yields (default: as "
                 "many as the device allows); the image does not depend on it"),
  };
  return specs;
}

PbgiParameters pbgiParameters(const Scene& scene) {
  const ResolvedParameters r = resolveParameterValues(scene, pbgiParameterSpecs());
  PbgiParameters p;
  const std::string variant = r.string("variant");
  p.variant = variant == "classic" ? PbgiParameters::Variant::Classic
              : variant == "mip"   ? PbgiParameters::Variant::Mip
                                   : PbgiParameters::Variant::X;
  p.microBuffer = int(r.integer("micro_buffer"));
  p.conservative = r.boolean("conservative");
  const std::string e = r.string("empty");
  p.empty = e == "auto"          ? PbgiParameters::Empty::Auto
            : e == "average"     ? PbgiParameters::Empty::Average
            : e == "environment" ? PbgiParameters::Empty::Environment
                                 : PbgiParameters::Empty::Black;
  p.prune = r.boolean("prune");
  p.meshes = r.boolean("meshes");
  p.bouncePoints = int(r.integer("bounce_points"));
  p.pairCapacity = int(r.integer("pair_capacity"));
  if (r.has("steps_per_dispatch")) p.stepsPerDispatch = int(r.integer("steps_per_dispatch"));
  return p;
}

MethodInfo pbgiMethodInfo() {
  MethodInfo m;
  m.name = "pbgi";
  m.summary =
      "real-time GI: point-based GI on a bounding-sphere hierarchy of the resident cut (GL)";
  m.gpu = true;
  m.qualityName = "micro-buffer m-pixels per side";
  m.defaultQualities = {8, 16, 32};
  m.applyQuality = [](GiSettings& g, int q) { setParameter(g, "micro_buffer", q); };
  m.create = createPbgiMethod;
  m.variants = {{"classic", [](GiSettings& g) { g.parameters["variant"] = "classic"; }},
                {"mip", [](GiSettings& g) { g.parameters["variant"] = "mip"; }},
                {"no pruning", [](GiSettings& g) { g.parameters["prune"] = false; }},
                {"conservative", [](GiSettings& g) { g.parameters["conservative"] = true; }},
                {"no meshes", [](GiSettings& g) { g.parameters["meshes"] = false; },
                 [](const Scene& s) -> std::string {
                   return s.meshes.empty() ? "the scene has no inserted mesh: the same image as "
                                             "pbgi's own"
                                           : "";
                 }}};
  m.parameters = rasterParameterSpecs();
  m.parameters.insert(m.parameters.end(), pbgiParameterSpecs().begin(), pbgiParameterSpecs().end());
  return m;
}

}  // namespace nestlight::gi
