// `nestlight make-scene`, `nestlight render scene.json` and `nestlight bench gi` end to end on
// small generated scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "test_support.h"

using namespace nestlight;

TEST(SceneCli, MakeSceneAndRenderBothModes) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(
      test::runCli("make-scene cornell -q -n 60k --width 24 --height 16 -o " + dir.file("cornell"),
                   &out),
      0)
      << out;
  const std::string scene = dir.file("cornell/scene.json");
  ASSERT_TRUE(std::filesystem::exists(scene));
  for (const char* mode : {"radiance_cache", "albedo"}) {
    std::string exr = dir.file(std::string("c_") + mode + ".exr");
    ASSERT_EQ(test::runCli("render " + scene + " --spp 4 --mode " + mode + " -o " + exr, &out), 0)
        << out;
    gi::ImageAttributes attrs;
    gi::HdrImage img = gi::readHdrImage(exr, &attrs);
    EXPECT_EQ(img.width, 24);
    EXPECT_EQ(img.height, 16);
    EXPECT_EQ(attrs["nestlight:samples"], "4");
    EXPECT_EQ(attrs["nestlight:mode"], mode);
    double sum = 0;
    for (float v : img.rgb) {
      ASSERT_TRUE(std::isfinite(v));
      sum += v;
    }
    EXPECT_GT(sum, 0) << mode << ": a lit room renders black";
  }
}

TEST(SceneCli, BadSceneFilesNameTheField) {
  test::TempDir dir;
  test::writeFile(
      dir.file("s.json"),
      R"({"meshes": [{"path": "a.obj", "material": {"type": "ggx", "roughness": 2}}]})");
  std::string out;
  EXPECT_EQ(test::runCli("render " + dir.file("s.json"), &out), 1);
  EXPECT_NE(out.find("scene.meshes[0].material.roughness"), std::string::npos) << out;
  test::writeFile(dir.file("box.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  test::writeFile(dir.file("nocam.json"), R"({"meshes": [{"path": "box.obj"}]})");
  EXPECT_EQ(test::runCli("render " + dir.file("nocam.json"), &out), 1);
  EXPECT_NE(out.find("scene.camera: missing"), std::string::npos) << out;
  test::writeFile(
      dir.file("t.json"),
      R"({"meshes": [{"path": "missing.obj"}], "camera": {"eye": [0, -1, 0], "target": [0, 0, 0]}})");
  EXPECT_EQ(test::runCli("render " + dir.file("t.json"), &out), 1);
  EXPECT_NE(out.find("missing.obj"), std::string::npos) << out;
}

// --param sets any member of gi.parameters, checked by the method's declaration as the scene
// file's members are; the declared flags (--variant) are checked by the command line.
TEST(SceneCli, ParamSetsAnyDeclaredParameter) {
  test::TempDir dir;
  test::writeFile(dir.file("box.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  test::writeFile(dir.file("s.json"),
                  R"({"meshes": [{"path": "box.obj"}], "lights": [{"type": "point", "position":
                      [0, 0, 2], "intensity": 1}], "camera": {"eye": [0.3, -2, 1], "target":
                      [0.3, 0.3, 0], "width": 8, "height": 8}, "gi": {"method": "raster"}})");
  const std::string render = "render " + dir.file("s.json") + " -o " + dir.file("s.exr");
  test::noLeakChecksInGlChildren();  // the last render runs the raster method
  std::string out;
  EXPECT_EQ(test::runCli(render + " --param shadow_map_size=5", &out), 1);
  EXPECT_NE(out.find("s.json: scene.gi.parameters.shadow_map_size: expected an integer in [16, "
                     "16384], got 5"),
            std::string::npos)
      << out;
  EXPECT_EQ(test::runCli(render + " --param shadow_map_sise=64", &out), 1);
  EXPECT_NE(out.find("scene.gi.parameters.shadow_map_sise: unknown field"), std::string::npos)
      << out;
  EXPECT_EQ(test::runCli(render + " --param shadow_map_size", &out), 1);
  EXPECT_NE(out.find("--param: expected KEY=VALUE"), std::string::npos) << out;
  EXPECT_NE(test::runCli(render + " --method pbgi --variant fast", &out), 0);
  EXPECT_NE(out.find("--variant"), std::string::npos) << out;
  ASSERT_EQ(test::runCli(render + " --param shadow_map_size=64 --param rasteriser=points", &out), 0)
      << out;
  EXPECT_NE(out.find("64 px shadow maps"), std::string::npos) << out;
}

TEST(SceneCli, BenchGiWritesTableAndPlot) {
  test::TempDir dir;
  std::string out;
  test::noLeakChecksInGlChildren();
  ASSERT_EQ(
      test::runCli("make-scene cornell -q -n 40k --width 16 --height 12 -o " + dir.file("c"), &out),
      0)
      << out;
  ASSERT_EQ(
      test::runCli(
          "bench gi " + dir.file("c/scene.json") +
              " --runs 1 --spp 1,4 --quality raster=64,256 --quality vpl=16 "
              "--quality pbgi=8 --quality ibl=2 --quality diffrender=8 --quality projection=1 "
              "--reference-error 0.05 "
              "--reference-spp 256 -o " +
              dir.file("b"),
          &out),
      0)
      << out;
  std::ifstream csv(dir.file("b/bench_gi.csv"));
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("method,variant,quality,quality_name", 0), 0u);
  int rows = 0;
  while (std::getline(csv, line)) rows++;
  // Every registered method that applies: reference and direct at 1 and 4 spp, raster at 2
  // shadow-map sizes, vpl at 16 VPLs as the scene sets it and with exact visibility (its 1 to 3
  // bounce variants skipped: in the radiance-cache mode, with one convex mesh, every bounce count
  // renders the same image), pbgi (X-PBGI) at 8 x 8 micro-buffers and in its 5 variants
  // (classic, mip, no pruning, conservative, no meshes); ibl skipped (no environment); diffrender
  // (the sphere is an inserted mesh) at 8 samples, and its em, vct, low and high variants;
  // projection at 1 importance sample per cluster and its random, splat 1, 2 and 3, every pixel,
  // grid and no glossy-to-glossy variants (1 bounce skipped: the radiance-cache mode).
  EXPECT_EQ(rows, 27 + 5);  // and the 5 skipped, each with its reason
  auto j = nlohmann::json::parse(test::readFile(dir.file("b/bench_gi.json")));
  ASSERT_EQ(j["rows"].size(), 27u);
  EXPECT_EQ(j["rows"][19]["method"], "projection");
  EXPECT_EQ(j["rows"][20]["variant"], "random");
  EXPECT_TRUE(j["rows"][19]["gpu_pass_ms"].contains("projection_gather_1")) << j["rows"][19].dump();
  EXPECT_EQ(j["rows"][14]["method"], "diffrender");
  EXPECT_EQ(j["rows"][15]["variant"], "em");
  EXPECT_TRUE(j["rows"][14]["gpu_pass_ms"].contains("diffrender_shade")) << j["rows"][14].dump();
  ASSERT_EQ(j["skipped"].size(), 5u) << j["skipped"].dump();
  EXPECT_EQ(j["skipped"][4]["method"], "projection");
  EXPECT_EQ(j["skipped"][4]["variant"], "1 bounce");
  EXPECT_EQ(j["skipped"][0]["variant"], "1 bounce");
  EXPECT_NE(j["skipped"][0]["reason"].get<std::string>().find("radiance-cache"), std::string::npos);
  EXPECT_EQ(j["skipped"][3]["method"], "ibl");
  EXPECT_EQ(j["skipped"][3]["variant"], "");
  EXPECT_NE(j["skipped"][3]["reason"].get<std::string>().find("no environment"), std::string::npos);
  EXPECT_NE(out.find("ibl: skipped (the scene has no environment"), std::string::npos) << out;
  EXPECT_EQ(j["rows"][8]["method"], "pbgi");
  EXPECT_EQ(j["rows"][9]["variant"], "classic");
  EXPECT_EQ(j["rows"][12]["variant"], "conservative");
  EXPECT_EQ(j["rows"][13]["variant"], "no meshes");
  EXPECT_TRUE(j["rows"][8]["gpu_pass_ms"].contains("pbgi_gather")) << j["rows"][8].dump();
  EXPECT_EQ(j["rows"][6]["method"], "vpl");
  EXPECT_EQ(j["rows"][6]["variant"], "");
  EXPECT_EQ(j["rows"][6]["quality_name"], "VPLs");
  EXPECT_TRUE(j["rows"][6]["gpu_pass_ms"].contains("ism")) << j["rows"][6].dump();
  EXPECT_EQ(j["rows"][7]["variant"], "exact visibility");
  EXPECT_TRUE(j["rows"][7]["attributes"].contains("nestlight:ism_agreement"))
      << j["rows"][7].dump();
  EXPECT_TRUE(j["rows"][6]["attributes"].contains("nestlight:clamp_loss"));
  // bench gi times every pass between glFinish() calls too (llvmpipe charges compute dispatches
  // to later passes' timer queries): one wall time per pass that ran.
  EXPECT_GT(std::stod(j["rows"][6]["attributes"]["nestlight:pass_wall_ms:ism"].get<std::string>()),
            0.0)
      << j["rows"][6]["attributes"].dump();
  EXPECT_EQ(j["rows"][4]["method"], "raster");
  EXPECT_EQ(j["rows"][4]["quality"], 64);
  EXPECT_EQ(j["rows"][5]["quality_name"], "shadow-map texels");
  EXPECT_TRUE(j["rows"][5]["gpu_pass_ms"].contains("shadow_maps")) << j["rows"][5].dump();
  EXPECT_TRUE(j["rows"][5]["gpu_pass_ms"].contains("direct_light"));
  // Rasterisation traces no rays: none counted, none printed as "0 rays/s".
  EXPECT_TRUE(j["rows"][5]["rays_per_second"].is_null());
  EXPECT_GT(j["rows"][0]["rays_per_second"].get<double>(), 0);
  EXPECT_TRUE(j.contains("time_to_1_percent"));
  EXPECT_NE(j["device"].get<std::string>().find("threads"), std::string::npos);
  // More samples, less error (4 spp against 1 spp of the same method).
  EXPECT_LT(j["rows"][3]["relative_l2"].get<double>(), j["rows"][2]["relative_l2"].get<double>());
  std::string svg = test::readFile(dir.file("b/bench_gi.svg"));
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  // The reference is cached: a second run does not render it again.
  ASSERT_EQ(
      test::runCli(
          "bench gi " + dir.file("c/scene.json") +
              " --runs 1 --spp 1 --methods direct --reference-error 0.05 --reference-spp 256 -o " +
              dir.file("b"),
          &out),
      0);
  EXPECT_EQ(out.find("rendering the reference"), std::string::npos) << out;
  // Set-up apart, the median of the runs: raster's set-up (making it: loading the scan, compiling
  // the GI frame's shaders on llvmpipe, hundreds of ms; and one first frame) is more than any of
  // its 16 x 12 frames at 64^2 shadow-map texels (a few ms).
  ASSERT_EQ(test::runCli("bench gi " + dir.file("c/scene.json") +
                             " --runs 3 --methods raster,ibl --quality raster=64 --no-variants "
                             "--reference-error 0.05 --reference-spp 256 -o " +
                             dir.file("b"),
                         &out),
            0)
      << out;
  j = nlohmann::json::parse(test::readFile(dir.file("b/bench_gi.json")));
  ASSERT_EQ(j["rows"].size(), 1u);
  std::vector<double> runs = j["rows"][0]["runs_ms"].get<std::vector<double>>();
  ASSERT_EQ(runs.size(), 3u);
  std::sort(runs.begin(), runs.end());
  EXPECT_EQ(j["rows"][0]["median_ms"].get<double>(), runs[1]);
  EXPECT_GT(j["rows"][0]["setup_ms"].get<double>(), runs[2]) << j["rows"][0].dump();
  EXPECT_EQ(j["skipped"].size(), 1u);
  const gi::HdrImage png = gi::readPng(dir.file("b/bench_gi.png"));
  EXPECT_GE(png.width, 800);
}

TEST(SceneCli, CameraPathRendersOneImagePerFrame) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(
      test::runCli("make-scene cornell -q -n 30k --width 8 --height 6 -o " + dir.file("c"), &out),
      0)
      << out;
  auto j = nlohmann::json::parse(test::readFile(dir.file("c/scene.json")));
  j["camera_path"] = {{"fps", 2},
                      {"keyframes",
                       {{{"time", 0}, {"eye", {2, 0.3, 2}}, {"target", {2, 3, 1}}},
                        {{"time", 1}, {"eye", {1, 0.3, 2}}, {"target", {2, 3, 1}}}}}};
  test::writeFile(dir.file("c/path.json"), j.dump());
  ASSERT_EQ(
      test::runCli("render " + dir.file("c/path.json") + " --spp 1 -o " + dir.file("f.exr"), &out),
      0)
      << out;
  // Frames at t = 0, 0.5 and 1 s; different views give different images.
  for (const char* f : {"f_0000.exr", "f_0001.exr", "f_0002.exr", "f_0000.png"})
    EXPECT_TRUE(std::filesystem::exists(dir.file(f))) << f;
  EXPECT_FALSE(std::filesystem::exists(dir.file("f_0003.exr")));
  EXPECT_NE(gi::readHdrImage(dir.file("f_0000.exr")).rgb,
            gi::readHdrImage(dir.file("f_0002.exr")).rgb);
  ASSERT_EQ(
      test::runCli("render " + dir.file("c/path.json") + " --spp 1 --still -o " + dir.file("s.exr"),
                   &out),
      0)
      << out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("s.exr")));
}

TEST(SceneCli, SurfelsOfAScaledBoxSumToItsArea) {
  // A unit box scaled by (2, 3, 4) at national-grid coordinates: 2(6 + 8 + 12) = 52 m^2, every
  // point on its surface, normals unit length, written through double so millimetres survive.
  test::TempDir dir;
  test::writeFile(dir.file("box.obj"),
                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
                  "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n");
  nlohmann::json scene = {
      {"origin", {500000.0, 5000000.0, 100.0}},
      {"materials", {{"red", {{"base_color", {0.5, 0.1, 0.1}}}}}},
      {"meshes",
       {{{"path", "box.obj"},
         {"material", "red"},
         {"transform", {{"translate", {500000.0, 5000000.0, 100.0}}, {"scale", {2, 3, 4}}}},
         {"surfels", {{"method", "poisson"}, {"count", 3000}}}}}}};
  test::writeFile(dir.file("scene.json"), scene.dump());
  std::string out;
  ASSERT_EQ(test::runCli("surfels " + dir.file("scene.json") + " -o " + dir.file("s.ply"), &out), 0)
      << out;
  auto reader = openReader(dir.file("s.ply"));
  test::Points pts = test::readAll(*reader);
  ASSERT_EQ(pts.size(), 3000u);
  double area = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    area += test::attrAt<float>(pts, *reader, i, "area");
    double x = pts.xyz[3 * i] - 500000.0, y = pts.xyz[3 * i + 1] - 5000000.0,
           z = pts.xyz[3 * i + 2] - 100.0;
    // On a face: one coordinate at 0 or its extent (within the 0.1 mm the PLY keeps plus float
    // rounding of local coordinates, 1e-3 m).
    double d = std::min(
        {std::abs(x), std::abs(x - 2), std::abs(y), std::abs(y - 3), std::abs(z), std::abs(z - 4)});
    ASSERT_LT(d, 1e-3) << x << " " << y << " " << z;
    float n[3] = {test::attrAt<float>(pts, *reader, i, "normal", 0),
                  test::attrAt<float>(pts, *reader, i, "normal", 1),
                  test::attrAt<float>(pts, *reader, i, "normal", 2)};
    ASSERT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5);
    ASSERT_EQ(test::attrAt<uint32_t>(pts, *reader, i, "material"), 0u);
  }
  // Float areas summed over 3000 points: 1e-5 relative.
  EXPECT_NEAR(area, 52.0, 52e-5);
}

// An explicit --time-limit wins over the scene's sample cap (gi.samples_per_pixel): without --spp
// the cap is lifted and the time limit stops the path tracer; with --spp the cap stands, and the
// render says that it, not the limit, stopped it. Which rule stopped it is read from the EXR, not
// from the wall time: a cap of 1 sample stops before the first check of the time limit (after
// every second sample, when both half images have one), a limit of a microsecond after it.
TEST(SceneCli, TimeLimitWinsOverTheScenesSampleCap) {
  test::TempDir dir;
  test::writeFile(dir.file("box.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  test::writeFile(dir.file("s.json"),
                  R"({"meshes": [{"path": "box.obj"}], "lights": [{"type": "point", "position":
                      [0, 0, 2], "intensity": 1}], "camera": {"eye": [0.3, -2, 1], "target":
                      [0.3, 0.3, 0], "width": 8, "height": 8},
                      "gi": {"method": "reference", "samples_per_pixel": 1}})");
  auto stop = [&](const std::string& options, std::string* out) {
    const std::string exr = dir.file("t.exr");
    std::filesystem::remove(exr);
    EXPECT_EQ(test::runCli("render " + dir.file("s.json") + " -o " + exr + " " + options, out), 0)
        << *out;
    gi::ImageAttributes attrs;
    gi::readHdrImage(exr, &attrs);
    return attrs["nestlight:stop"] + " at " + attrs["nestlight:samples"];
  };
  std::string out;
  EXPECT_EQ(stop("", &out), "samples at 1") << out;
  EXPECT_EQ(stop("--time-limit 0.000001", &out), "time limit at 2") << out;
  EXPECT_FALSE(out.find("the sample cap stopped it") != std::string::npos) << out;
  EXPECT_EQ(stop("--time-limit 0.000001 --spp 1", &out), "samples at 1") << out;
  EXPECT_NE(out.find("render: the sample cap stopped it at 1 spp (--spp), before --time-limit did"),
            std::string::npos)
      << out;
  // --target-error does not lift the cap (an error target may never be reached); it says so.
  EXPECT_EQ(stop("--target-error 0.000001", &out), "samples at 1") << out;
  EXPECT_NE(out.find("the sample cap stopped it at 1 spp (the scene's gi.samples_per_pixel"),
            std::string::npos)
      << out;
}
