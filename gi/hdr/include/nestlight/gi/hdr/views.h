// The views HDR expansion renders the scan from (Sabbadin et al., "High Dynamic Range Point
// Clouds for Real-Time Relighting", 2019, section 4.1: LDR renderings whose camera matrices are
// kept for back-projection). A view is a pinhole camera in world coordinates; positions stay
// doubles so that a national-grid scan projects without jitter (points are made relative to the
// camera before anything is rounded to float).
//
// Views come from a file (cams.json, docs/HDR.md) or automatically: cube maps (six 90-degree
// faces, as the paper's shots) placed to see the scan's over-exposed points.
#pragma once

#include <filesystem>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace nestlight::gi::hdr {

struct View {
  std::string name;
  glm::dvec3 position{0};
  glm::dvec3 forward{0, 0, -1};  // unit
  glm::dvec3 up{0, 0, 1};        // unit, orthogonal to forward
  double fovYDegrees = 90;
  int width = 512, height = 512;

  glm::dvec3 right() const { return glm::normalize(glm::cross(forward, up)); }
  // Focal length in pixels (vertical).
  double focalPixels() const;
  // Projects a world position: pixel coordinates (x right, y down, pixel centres at +0.5) and
  // the depth along `forward`; false when behind the camera (depth <= 1e-9).
  bool project(const glm::dvec3& world, glm::dvec2& pixel, double& depth) const;
  // 4x4 matrices kept with the renderings (GL conventions, view space looking down -z):
  // viewFromWorld includes the translation; clipFromView is the projection (near, far given).
  glm::dmat4 viewFromWorld() const;
  glm::dmat4 clipFromView(double near, double far) const;
};

// A view looking from `position` towards `target`, with `up` made orthogonal (world z when
// `up` is parallel to the view direction).
View lookAt(const glm::dvec3& position, const glm::dvec3& target, glm::dvec3 up, double fovYDegrees,
            int width, int height);
// The six 90-degree faces of a cube map at `position` (+x, -x, +y, -y, +z, -z), named
// "<name>+x" and so on.
std::vector<View> cubeMap(const std::string& name, const glm::dvec3& position, int size);

// cams.json: {"views": [{"name": ..., "position": [x,y,z], "look_at": [x,y,z] | "forward": [...],
// "up": [...], "fov_y": 60, "width": 512, "height": 512} | {"cube_map": [x,y,z], "size": 512}]}.
// Throws nestlight::Error naming the file and the field.
std::vector<View> readViews(const std::filesystem::path& file);
// Writes the views with their matrices (for back-projection by other tools), atomically.
void writeViews(const std::filesystem::path& file, const std::vector<View>& views);
nlohmann::json viewToJson(const View& v);

}  // namespace nestlight::gi::hdr
