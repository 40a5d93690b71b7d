// Set 1 of the software micro-raster (sw_raster.comp.glsl, sw_merge.frag.glsl, engine/passes/sw_raster_pass.cpp).
#ifndef VISBUF_BINDINGS_SW_RASTER_H
#define VISBUF_BINDINGS_SW_RASTER_H

#define SW_RASTER_BINDING_DRAWS 0       // DrawCommand[] (the cull pass's)
#define SW_RASTER_BINDING_DRAW_LISTS 1  // uvec4[DRAW_LISTS] (config.h DRAW_LIST_*)
// uint64 per pixel: reverse-Z depth bits << 32 | payload, atomicMax'ed; 0 = nothing.
#define SW_RASTER_BINDING_VISIBILITY 2
// The same buffer as RG32UI texels (x: the complemented payload, y: the depth bits): what the merge reads (on lavapipe
// a texel fetch is one vector load, a storage-buffer read a bounds-checked scalar load per lane and word).
#define SW_RASTER_BINDING_VISIBILITY_TEXELS 3

#endif
