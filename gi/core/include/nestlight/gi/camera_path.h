// Camera paths, one definition for scene files ("camera_path") and `nestlight render --path`
// files: keyframes of eye and target at times (seconds), interpolated linearly and sampled at
// `fps` from the first key's time to the last's.
#pragma once

#include <filesystem>
#include <glm/glm.hpp>
#include <optional>
#include <vector>

namespace nestlight {
class JsonField;
}

namespace nestlight::gi {

struct CameraKey {
  double time = 0;
  glm::dvec3 eye{0.0}, target{0.0};
};

struct CameraPath {
  double fps = 30;
  std::optional<double> fovYDegrees;  // `render --path` files may set the field of view
  std::vector<CameraKey> keys;        // times increase

  bool empty() const { return keys.empty(); }
  // 1 + floor((last - first) * fps): a path of one key, or of keys closer than a frame, is one
  // frame.
  int frames() const;
  // Eye and target at frame `frame` (time first + frame / fps), clamped to the last key.
  CameraKey at(int frame) const;
};

// {"fps": 30, "keyframes": [{"time": 0, "eye": [x, y, z], "target": [x, y, z]}, ...]} (and "fov"
// in degrees when `allowFov`). Throws nestlight::Error naming the file and field: no keys, times
// that do not increase, an eye on its target, more than a million frames.
CameraPath parseCameraPath(const JsonField& field, bool allowFov);
// A `nestlight render --path` file.
CameraPath loadCameraPath(const std::filesystem::path& file);

}  // namespace nestlight::gi
