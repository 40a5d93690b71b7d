// Set 1 of the G-buffer lighting (gbuffer_lighting.comp.glsl, engine/passes/gbuffer_lighting_pass.cpp):
// lighting.glsl's, then its own.
#ifndef VISBUF_BINDINGS_GBUFFER_LIGHTING_H
#define VISBUF_BINDINGS_GBUFFER_LIGHTING_H

#include "bindings_lighting.h"

#define GBUFFER_LIGHTING_BINDING_TARGETS (LIGHTING_BINDINGS + 0)     // sampler2D[GBUFFER_TARGETS]
#define GBUFFER_LIGHTING_BINDING_DEPTH (LIGHTING_BINDINGS + 1)       // sampler2D: the frame's D32 depth (reverse-Z)
#define GBUFFER_LIGHTING_BINDING_COLOR (LIGHTING_BINDINGS + 2)       // rgba16f output image
#define GBUFFER_LIGHTING_BINDING_ATTRIBUTES (LIGHTING_BINDINGS + 3)  // float[ATTRIBUTE_FLOATS] per pixel

#endif
