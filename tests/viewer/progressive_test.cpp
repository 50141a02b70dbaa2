// The progressive view of the path tracer (nestlight/viewer/progressive.h) without a window: its
// running mean converges to the method's own render of the view, a camera move restarts it, and
// paused it samples nothing.
#include "nestlight/viewer/progressive.h"

#include <cmath>

#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/scene.h"
#include "test_support.h"

TEST(Progressive, ConvergesRestartsWhenTheCameraMovesAndPauses) {
  nestlight::test::TempDir tmp;
  std::string out;
  ASSERT_EQ(nestlight::test::runCli(
                "make-scene cornell -q -n 20k --width 48 --height 36 -o " + tmp.file("c"), &out),
            0)
      << out;
  nestlight::gi::Scene scene = nestlight::gi::loadScene(tmp.file("c/scene.json"));
  scene.gi.samplesPerPixel = 512;
  scene.gi.targetRelativeError = 0;
  const nestlight::gi::MethodContext quiet(true);
  nestlight::gi::SceneCamera cam = scene.camera, moved = scene.camera;
  moved.target += glm::dvec3(1.5, 0, 0);  // a third of the room to the side
  // The truths: the method's own renders, 512 samples per pixel (its error a quarter of a
  // 32-sample mean's).
  std::unique_ptr<nestlight::gi::Method> m = nestlight::gi::createMethod(scene, quiet);
  ASSERT_TRUE(m->rendersInBatches());
  const nestlight::gi::HdrImage truth = m->render(cam).image;
  const nestlight::gi::HdrImage truthMoved = m->render(moved).image;

  nestlight::viewer::ProgressiveView view(std::move(m), 32);
  view.setCamera(cam);
  ASSERT_TRUE(view.waitFor(1, 60));
  const nestlight::viewer::ProgressiveView::Snapshot first = view.snapshot();
  ASSERT_TRUE(view.waitFor(32, 60));
  const nestlight::viewer::ProgressiveView::Snapshot done = view.snapshot();
  EXPECT_EQ(done.samplesPerPixel, 32);
  EXPECT_TRUE(done.complete);
  EXPECT_EQ(done.mean.width, 48);  // small enough for full resolution
  const double errorFirst = nestlight::gi::relativeL2(first.mean, truth);
  const double errorDone = nestlight::gi::relativeL2(done.mean, truth);
  // A mean of n samples has 1 / sqrt(n) of one sample's error: at least twice the samples must
  // show (a factor sqrt(2) expected; 0.85 keeps clear of the noise of the estimate itself).
  if (first.samplesPerPixel <= 16) {
    EXPECT_LT(errorDone, 0.85 * errorFirst);
  }
  EXPECT_LT(errorDone, 0.5) << "the mean is not the view's image";

  // A camera move: the accumulation starts again from the new view (the old samples would leave
  // the first view's image in it).
  view.setCamera(moved);
  ASSERT_TRUE(view.waitFor(32, 60));
  const nestlight::viewer::ProgressiveView::Snapshot after = view.snapshot();
  EXPECT_EQ(after.samplesPerPixel, 32);
  EXPECT_LT(nestlight::gi::relativeL2(after.mean, truthMoved),
            0.6 * nestlight::gi::relativeL2(after.mean, truth));
  EXPECT_LT(nestlight::gi::relativeL2(after.mean, truthMoved), 1.2 * errorDone);

  // Paused (the window shows the points), nothing is sampled for a new view; resumed, it is.
  view.setPaused(true);
  view.setCamera(cam);
  EXPECT_FALSE(view.waitFor(1, 1.0));
  EXPECT_EQ(view.snapshot().version, after.version);
  view.setPaused(false);
  ASSERT_TRUE(view.waitFor(32, 60));
  EXPECT_LT(nestlight::gi::relativeL2(view.snapshot().mean, truth), 1.2 * errorDone);
}
