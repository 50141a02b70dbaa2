// The scene's environment as a renderer plays it over a shot: a constant, one map, or a video
// light probe (nestlight/gi/environment_sequence.h) whose frame follows the camera's time. Every
// renderer (the reference and the GL methods) asks the same object, so the frame a method lights
// with at time t is the frame its ground truth lit with.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>

#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/environment_sequence.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

class EnvironmentSource {
 public:
  // `e` empty: no environment (a black map, never sampled). Reads a map at once (an error names
  // its file); a sequence's frames are read as they are asked for.
  explicit EnvironmentSource(const std::optional<SceneEnvironment>& e);

  bool present() const { return present_; }
  bool isSequence() const { return sequence_ != nullptr; }
  // Which frame plays at `seconds` (0 without a sequence).
  size_t frameAt(double seconds) const;
  size_t frames() const;
  // The map to light with at `seconds` (the constant or the single map at any time). Throws
  // nestlight::Error naming a frame that cannot be read (unless the scene keeps the previous one).
  std::shared_ptr<const EnvironmentMap> at(double seconds);
  const EnvironmentSequence* sequence() const { return sequence_.get(); }

 private:
  bool present_ = false;
  std::shared_ptr<const EnvironmentMap> still_;
  std::unique_ptr<EnvironmentSequence> sequence_;
};

}  // namespace nestlight::gi
