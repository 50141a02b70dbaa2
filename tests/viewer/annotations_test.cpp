// Overlays drawn into images (render and screenshots): measurement lines clipped to the image even
// when a vertex projects to enormous coordinates, labels inside the frame, text that stb_easy_font
// cannot draw replaced rather than read out of its glyph table, labels in the scan's unit.
#include "nestlight/viewer/annotations.h"

#include <gtest/gtest.h>

namespace annotations_test {

using namespace nestlight;
using namespace nestlight::viewer;

frame::Camera lookingAtOrigin() {
  frame::Camera c;
  c.eye = {0, -10, 0};
  c.target = {0, 0, 0};
  c.nearPlane = 0.05;
  c.farPlane = 100;
  return c;
}

frame::Image blank(int w, int h) {
  frame::Image img;
  img.width = w, img.height = h;
  img.rgba.assign(size_t(w) * h * 4, 0.0f);
  return img;
}

size_t changed(const frame::Image& img) {
  size_t n = 0;
  for (size_t i = 0; i < img.rgba.size(); i += 4) n += img.rgba[i] + img.rgba[i + 1] > 0;
  return n;
}

TEST(Overlay, ALineToAPointBesideTheEyeIsClippedNotOverflowed) {
  frame::Image img = blank(64, 48);
  Measurement m;
  m.kind = Measurement::Kind::Distance;
  // The second vertex sits just in front of the near plane, far to the side: its projection lies
  // some 1e7 image widths away (unclipped, 1e9 steps of the line).
  m.points = {{0, 0, 0}, {1e6, -9.94, 0}};
  EXPECT_EQ(drawMeasurements(img, lookingAtOrigin(), {m}, "m"), 1);
  EXPECT_GT(changed(img), 20u);  // from the centre to the right edge
  // A segment wholly behind the eye draws nothing.
  frame::Image none = blank(64, 48);
  m.points = {{0, -20, 0}, {1, -30, 0}};
  EXPECT_EQ(drawMeasurements(none, lookingAtOrigin(), {m}, "m"), 0);
  EXPECT_EQ(changed(none), 0u);
}

TEST(Overlay, LabelsStayInTheFrameAndDrawOnlyAscii) {
  frame::Image img = blank(96, 64);
  frame::Annotation a;
  a.position = {2.5, 0, 2.5};  // near the top-right corner
  a.title = "crack \xC3\xA9 A\xC2\xB2 with a title far longer than the image is wide";
  EXPECT_EQ(drawAnnotations(img, lookingAtOrigin(), {a}), 1);
  EXPECT_GT(changed(img), 30u);
  a.position = {0, -20, 0};  // behind the eye
  frame::Image none = blank(96, 64);
  EXPECT_EQ(drawAnnotations(none, lookingAtOrigin(), {a}), 0);
  EXPECT_EQ(changed(none), 0u);
}

TEST(Overlay, MeasurementLabelsInTheScansUnit) {
  Measurement d;
  d.kind = Measurement::Kind::Distance;
  d.points = {{512000, 5412000, 300}, {512003, 5412004, 300}};
  EXPECT_EQ(measurementLabel(d, "ft"), "5.000 ft");
  Measurement area;
  area.kind = Measurement::Kind::Area;
  area.points = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}};
  EXPECT_EQ(measurementLabel(area, "m"), "6.000 m^2");
  Measurement angle;
  angle.kind = Measurement::Kind::Angle;
  angle.points = {{1, 0, 0}, {0, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(measurementLabel(angle, "m"), "90.0 deg");
  angle.points.pop_back();  // incomplete: no label
  EXPECT_EQ(measurementLabel(angle, "m"), "");
}

}  // namespace annotations_test
