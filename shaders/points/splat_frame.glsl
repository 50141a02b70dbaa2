// Which frame the splatting passes of this folder serve: the point view (0, the default) or the
// GI frame's G-buffer (1: positions in the scene's local frame; nestlight/frame/point_splatting.h
// compiles them with NL_SCENE_FRAME 1 there).
#ifndef NL_SCENE_FRAME
#define NL_SCENE_FRAME 0
#endif
