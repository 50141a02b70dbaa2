// libFuzzer target for scene files: any bytes either parse into a scene or throw
// nestlight::Error (JSON syntax errors included, with their byte); never an abort, an uncaught
// nlohmann exception or undefined behaviour.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "nestlight/gi/scene.h"
#include "nestlight/octree/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  try {
    nestlight::gi::Scene s = nestlight::gi::parseScene(j, "/fuzz/scene.json");
    if (s.octrees.empty() && s.meshes.empty()) __builtin_trap();  // parseScene promises one
  } catch (const nestlight::Error&) {
  }
  return 0;
}
