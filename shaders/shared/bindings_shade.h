// Set 1 of the shading pass (shade.comp.glsl, covered_pixels.comp.glsl, msaa_ids.comp.glsl, visibility_id.glsl,
// msaa_samples.glsl; engine/passes/shade_pass.cpp): lighting.glsl's, then its own. The classified shading
// (bindings_classify.h) is the same shader: it has these numbers too.
#ifndef VISBUF_BINDINGS_SHADE_H
#define VISBUF_BINDINGS_SHADE_H

#include "bindings_lighting.h"

#define SHADE_BINDING_DRAWS (LIGHTING_BINDINGS + 0)       // DrawCommand[] (the cull pass's)
#define SHADE_BINDING_DRAW_TEXELS (LIGHTING_BINDINGS + 1) // the same as R32UI texels (five words per DrawCommand)
#define SHADE_BINDING_VISIBILITY (LIGHTING_BINDINGS + 2)  // usampler2D (usampler2DMS with MSAA): the ID target
#define SHADE_BINDING_COLOR (LIGHTING_BINDINGS + 3)       // rgba16f output image
// float[ATTRIBUTE_FLOATS] per pixel: the attributes variant's reconstruction; the sample-ID copy (msaa_ids.comp).
#define SHADE_BINDING_ATTRIBUTES (LIGHTING_BINDINGS + 4)
#define SHADE_BINDING_DEPTH (LIGHTING_BINDINGS + 5)       // sampler2D: the depth (the SW_RESOLVE variants read it)
#define SHADE_BINDING_IDS_STORAGE (LIGHTING_BINDINGS + 6) // the single-sampled ID target as a storage image (clear_ids.comp)
// The micro-raster's buffer as RG32UI texels (bindings_sw_raster.h SW_RASTER_BINDING_VISIBILITY_TEXELS): the SW_RESOLVE
// variants read it.
#define SHADE_BINDING_SW_TEXELS (LIGHTING_BINDINGS + 7)
// The covered-pixel list (FrameData.coveredPixels*) as R32UI texels: the covered shading reads it so where VB_TEXELS.
#define SHADE_BINDING_COVERED_TEXELS (LIGHTING_BINDINGS + 8)

#endif
