// The methods' parameter declarations (nestlight/gi/method_parameters.h): what each method
// declares is what it accepts, and a scene that gives nothing gets the declared defaults.
#include "nestlight/gi/method_parameters.h"

#include <gtest/gtest.h>

#include <set>

#include "nestlight/gi/ibl/ibl_method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/pbgi/pbgi_method.h"
#include "nestlight/gi/raster/raster_method.h"
#include "nestlight/gi/vpl/vpl_method.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

using json = nlohmann::json;

// Each method's declared parameters: one declaration per name, every default one the method
// accepts when a scene gives it, and a scene giving none resolves to the defaults.
TEST(Methods, DeclaredParametersResolveToTheirDefaults) {
  for (const auto& m : registeredMethods()) {
    std::set<std::string> names;
    Scene s;
    s.file = "/scenes/" + m.name + ".json";
    s.gi.method = m.name;
    for (const auto& p : m.parameters) {
      EXPECT_TRUE(names.insert(p.name).second) << m.name << ": " << p.name << " declared twice";
      EXPECT_FALSE(p.help.empty()) << m.name << ": " << p.name;
      if (p.defaultValue.is_null()) continue;  // the method picks the value
      s.gi.parameters = json{{p.name, p.defaultValue}};
      try {
        EXPECT_EQ(resolveParameters(s, m.parameters).value(p.name), p.defaultValue)
            << m.name << ": " << p.name;
      } catch (const Error& e) {
        ADD_FAILURE() << m.name << ": the default of " << p.name << " is refused: " << e.what();
      }
    }
    for (const json& none : {json(), json::object()}) {
      s.gi.parameters = none;
      const ResolvedParameters r = resolveParameters(s, m.parameters);
      for (const auto& p : m.parameters)
        EXPECT_EQ(r.value(p.name), p.defaultValue) << m.name << ": " << p.name;
    }
  }
}

// The typed parameters' initial values are the declared defaults: a method made in code (tests,
// benchmarks) and one made from a scene without gi.parameters run the same.
TEST(Methods, TypedParametersStartAtTheDeclaredDefaults) {
  Scene s;
  s.file = "/scenes/defaults.json";
  for (const json& none : {json(), json::object()}) {
    s.gi.parameters = none;
    const FrameParameters r = rasterParameters(s), r0;
    EXPECT_EQ(r.shadowMapSize, r0.shadowMapSize);
    EXPECT_EQ(r.computeRasteriser, r0.computeRasteriser);
    EXPECT_EQ(r.hqs, r0.hqs);
    EXPECT_EQ(r.splatScale, r0.splatScale);
    EXPECT_EQ(r.pointBudget, r0.pointBudget);
    EXPECT_EQ(r.gpuBytes, r0.gpuBytes);
    EXPECT_EQ(r.maxTile, r0.maxTile);
    EXPECT_EQ(r.streamTimeoutSeconds, r0.streamTimeoutSeconds);
    const PbgiParameters p = pbgiParameters(s), p0;
    EXPECT_EQ(p.variant, p0.variant);
    EXPECT_EQ(p.pairCapacity, p0.pairCapacity);
    EXPECT_EQ(p.microBuffer, p0.microBuffer);
    EXPECT_EQ(p.conservative, p0.conservative);
    EXPECT_EQ(p.empty, p0.empty);
    EXPECT_EQ(p.prune, p0.prune);
    EXPECT_EQ(p.meshes, p0.meshes);
    EXPECT_EQ(p.bouncePoints, p0.bouncePoints);
    EXPECT_EQ(p.stepsPerDispatch, p0.stepsPerDispatch);
    const VplParameters v = vplParameters(s), v0;
    EXPECT_EQ(v.count, v0.count);
    EXPECT_EQ(v.autoCount, v0.autoCount);
    EXPECT_EQ(v.targetMs, v0.targetMs);
    EXPECT_EQ(v.lightResolution, v0.lightResolution);
    EXPECT_EQ(v.ismSize, v0.ismSize);
    EXPECT_EQ(v.ismPoints, v0.ismPoints);
    EXPECT_EQ(v.pullPushLevels, v0.pullPushLevels);
    EXPECT_EQ(v.interleave, v0.interleave);
    EXPECT_EQ(v.clampFraction, v0.clampFraction);
    EXPECT_EQ(v.ismBias, v0.ismBias);
    EXPECT_EQ(v.lodScale, v0.lodScale);
    EXPECT_EQ(v.energyStop, v0.energyStop);
    EXPECT_EQ(v.visibility, v0.visibility);
    const IblParameters i = iblParameters(s), i0;
    EXPECT_EQ(i.estimator, i0.estimator);
    EXPECT_EQ(i.brdfSamples, i0.brdfSamples);
    EXPECT_EQ(i.envSamples, i0.envSamples);
    EXPECT_EQ(i.bisProposals, i0.bisProposals);
    EXPECT_EQ(i.bisSamples, i0.bisSamples);
    EXPECT_EQ(i.smcParticles, i0.smcParticles);
    EXPECT_EQ(i.smcIntermediate, i0.smcIntermediate);
    EXPECT_EQ(i.smcLocalProbability, i0.smcLocalProbability);
    EXPECT_EQ(i.smcLocalDegrees, i0.smcLocalDegrees);
    EXPECT_EQ(i.smcReinitRatio, i0.smcReinitRatio);
    EXPECT_EQ(i.smcReinitOnDrop, i0.smcReinitOnDrop);
    EXPECT_EQ(i.visibility, i0.visibility);
    EXPECT_EQ(i.smcStatistics, i0.smcStatistics);
    EXPECT_EQ(i.smcBandRows, i0.smcBandRows);
  }
}

// The resolver's checks are the scene validator's: the same messages, naming the file and
// scene.gi.parameters.<key>, in the order the parameters are declared.
TEST(Methods, ResolvingChecksNamesTypesRangesAndChoices) {
  const ParameterSpecs specs = {
      ParameterSpec::integer("size", 8, 512, 32, "texels").powersOfTwo(),
      ParameterSpec::integer("count", 1, 100, 10, "items").orOneOf({"auto"}),
      ParameterSpec::number("scale", 0.5, 2, 1, "times"),
      ParameterSpec::boolean("on", true, "switch"),
      ParameterSpec::choice("kind", {"a", "b"}, "a", "which")};
  Scene s;
  s.file = "/scenes/s.json";
  auto message = [&](const json& p) {
    s.gi.parameters = p;
    try {
      resolveParameters(s, specs);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({{"size", 48}}),
            "/scenes/s.json: scene.gi.parameters.size: must be a power of two (8 to 512)");
  EXPECT_EQ(message({{"size", 4}}),
            "/scenes/s.json: scene.gi.parameters.size: expected an integer in [8, 512], got 4");
  EXPECT_EQ(message({{"count", "many"}}),
            "/scenes/s.json: scene.gi.parameters.count: 'many' is not one of: auto");
  EXPECT_EQ(message({{"scale", 3}}),
            "/scenes/s.json: scene.gi.parameters.scale: expected a number in [0.5, 2], got 3");
  EXPECT_EQ(message({{"on", 1}}),
            "/scenes/s.json: scene.gi.parameters.on: expected true or false, got number");
  EXPECT_EQ(message({{"kind", "c"}}),
            "/scenes/s.json: scene.gi.parameters.kind: 'c' is not one of: a, b");
  EXPECT_EQ(message({{"sise", 8}}),
            "/scenes/s.json: scene.gi.parameters.sise: unknown field (expected one of: count, "
            "kind, on, scale, size)");
  EXPECT_EQ(message({{"kind", "c"}, {"scale", 3}}),
            "/scenes/s.json: scene.gi.parameters.scale: expected a number in [0.5, 2], got 3");
  EXPECT_EQ(message({{"count", "auto"}, {"size", 64}}), "accepted");
  s.gi.parameters = {{"count", "auto"}, {"size", 64}};
  const ResolvedParameters r = resolveParameters(s, specs);
  EXPECT_EQ(r.value("count"), "auto");
  EXPECT_EQ(r.integer("size"), 64);
  EXPECT_EQ(r.number("scale"), 1.0);
  EXPECT_TRUE(r.boolean("on"));
  EXPECT_EQ(r.string("kind"), "a");
}

}  // namespace
}  // namespace nestlight::gi
