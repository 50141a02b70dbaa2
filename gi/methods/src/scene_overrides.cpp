#include "nestlight/gi/scene_overrides.h"

namespace nestlight::gi {

void applySceneOverrides(Scene& scene, const SceneRenderOverrides& ov) {
  if (ov.width) scene.camera.width = *ov.width;
  if (ov.height) scene.camera.height = *ov.height;
  if (ov.camera) {
    scene.camera.eye = ov.camera->eye;
    scene.camera.target = ov.camera->target;
    scene.camera.up = ov.camera->up;
    scene.cameraSet = true;
  }
  if (ov.fov) scene.camera.fovYDegrees = *ov.fov;
  for (SceneOctree& o : scene.octrees)
    o.clipping.volumes.insert(o.clipping.volumes.end(), ov.clipping.volumes.begin(),
                              ov.clipping.volumes.end());
  if (ov.method) scene.gi.method = *ov.method;
  if (ov.mode) scene.gi.mode = *ov.mode;
  if (ov.bounces) scene.gi.maxBounces = *ov.bounces;
  if (ov.spp) scene.gi.samplesPerPixel = *ov.spp;
  if (ov.targetError) scene.gi.targetRelativeError = *ov.targetError;
  if (ov.timeLimit) scene.gi.timeLimitSeconds = *ov.timeLimit;
  if (ov.seed) scene.gi.seed = *ov.seed;
  if (ov.parameters.is_object() && !ov.parameters.empty()) {
    if (!scene.gi.parameters.is_object()) scene.gi.parameters = nlohmann::json::object();
    scene.gi.parameters.update(ov.parameters);
  }
}

}  // namespace nestlight::gi
