// Annotations over a rendered image: each label's marker at its point and its title beside it,
// as the viewer draws them, for `render` (a view state's annotations reach stills and paths).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/frame/image.h"
#include "nestlight/frame/view_state.h"

namespace nestlight::viewer {

// Where `world` lands in a width x height image seen by `camera` (pixels, top-left origin); none
// behind the eye or outside the image.
std::optional<glm::dvec2> projectToImage(const frame::Camera& camera, int width, int height,
                                         const Vec3d& world);

// Draws the annotations that lie in front of the camera and inside the frame; returns how many.
// Text is drawn with stb_easy_font (Debian's libstb), scaled with the image's height.
int drawAnnotations(frame::Image& image, const frame::Camera& camera,
                    const std::vector<frame::Annotation>& annotations);

// A measurement's value as its label over the view shows it: "10.606 m", "12.250 m^2",
// "dz 1.234 m", "34.2 deg" (the panel shows Measurement::describe, with the plan parts).
std::string measurementLabel(const Measurement& m, const std::string& unit);

// Draws each measurement's lines (a polygon closed) and its value (measurementLabel in
// `unit`) by its last point; returns how many had a point in the frame.
int drawMeasurements(frame::Image& image, const frame::Camera& camera,
                     const std::vector<Measurement>& measurements, const std::string& unit);

}  // namespace nestlight::viewer
