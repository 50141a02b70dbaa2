// The GI frame's interface moved to gi/frame (nestlight/gi/frame/raster_frame.h); this header
// forwards to it until vpl, pbgi, ibl and gi/shared include it from there.
#pragma once

#include "nestlight/gi/frame/raster_frame.h"
