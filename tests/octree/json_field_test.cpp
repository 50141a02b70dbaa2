// The one JSON validator: every error names the file and the field.
#include "nestlight/octree/json_field.h"

#include <gtest/gtest.h>

#include "nestlight/octree/error.h"
#include "nestlight/octree/metadata.h"
#include "test_support.h"

using namespace nestlight;
using nlohmann::json;

namespace {

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(JsonField, ErrorsNameTheFileAndTheField) {
  const json j = json::parse(R"({"a": {"b": [1, "x", 3]}, "n": -2, "s": "hqs", "extra": 1})");
  const JsonField f(j, "scene", "s.json");
  EXPECT_EQ(f.at("a").at("b").at(size_t(2)).number(), 3.0);
  auto has = [](const std::string& msg, const std::string& want) {
    return msg.find(want) != std::string::npos;
  };
  EXPECT_TRUE(has(messageOf([&] { f.at("a").at("b").at(size_t(1)).number(); }), "scene.a.b[1]"));
  EXPECT_TRUE(has(messageOf([&] { f.at("a").at("b").at(size_t(1)).number(); }), "s.json"));
  EXPECT_TRUE(has(messageOf([&] { f.at("missing"); }), "missing \"missing\""));
  EXPECT_TRUE(has(messageOf([&] { f.at("n").count(); }), "non-negative integer"));
  EXPECT_TRUE(has(messageOf([&] { f.at("n").integer(0, 5); }), "[0, 5]"));
  EXPECT_TRUE(has(messageOf([&] {
                    f.at("s").choice({"basic", "soft"});
                  }),
                  "'hqs' is not one of: basic, soft"));
  EXPECT_TRUE(has(messageOf([&] {
                    f.expectObject({"a", "n", "s"});
                  }),
                  "scene.extra: unknown field"));
  EXPECT_TRUE(has(messageOf([&] { f.at("a").at("b").vec3(); }), "scene.a.b[1]"));
}

TEST(JsonField, MetadataErrorsNameTheField) {
  test::TempDir t;
  test::writeFile(t.file("bad.json"),
                  "{\"format\": \"nestlight-octree\", \"version\": 2,\n  \"points\": oops}");
  const std::string syntax = messageOf([&] { readJsonFile(t.file("bad.json")); });
  EXPECT_NE(syntax.find("bad.json"), std::string::npos) << syntax;
  EXPECT_NE(syntax.find("byte"), std::string::npos) << syntax;
  const json m =
      json::parse(R"({"format": "nestlight-octree", "version": 2, "points": 1, "nodes": 1,
      "bounds": null, "offset": [0, 0, 0], "scale": -1})");
  const std::string scale = messageOf([&] { Metadata::fromJson(m, "metadata.json"); });
  EXPECT_NE(scale.find("metadata.json"), std::string::npos) << scale;
  EXPECT_NE(scale.find("scale: must be positive"), std::string::npos) << scale;
  json noPoints = m;
  noPoints.erase("points");
  EXPECT_NE(
      messageOf([&] { Metadata::fromJson(noPoints, "metadata.json"); }).find("missing \"points\""),
      std::string::npos);
}

// A number beyond a double is an error naming the file, the line and the field (the parser
// alone names only the literal).
TEST(JsonField, ANumberBeyondADoubleNamesFileLineAndField) {
  test::TempDir t;
  test::writeFile(t.file("scene.json"),
                  "{\n  \"lights\": [\n    {\"type\": \"point\", \"intensity\": 1e400}\n  ]\n}\n");
  const std::string m = messageOf([&] { readJsonFile(t.file("scene.json")); });
  EXPECT_NE(m.find(t.file("scene.json") + ": line 3: field \"intensity\": the number 1e400"),
            std::string::npos)
      << m;
}

}  // namespace
