// What the command line changes in a loaded scene before a method is made from it: the image
// size, the method and its settings and parameters (SceneRenderOverrides). `nestlight view` applies
// them here; the same fields as `nestlight render` takes (nestlight/gi/render_scene.h).
#pragma once

#include "nestlight/gi/render_scene.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

// Width, height, camera, field of view, method, mode, bounces, samples, error target, time limit,
// seed, the parameters merged into scene.gi.parameters and the clipping volumes added to every
// scan's. The output fields are left to the caller.
void applySceneOverrides(Scene& scene, const SceneRenderOverrides& overrides);

}  // namespace nestlight::gi
