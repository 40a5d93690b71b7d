// Set 1 of the G-buffer raster (gbuffer.frag.glsl, engine/passes/gbuffer_pass.cpp). It declares lighting.glsl's
// bindings through material.glsl (never used): the overdraw image comes after them.
#ifndef VISBUF_BINDINGS_GBUFFER_H
#define VISBUF_BINDINGS_GBUFFER_H

#include "bindings_lighting.h"

#define GBUFFER_BINDING_OVERDRAW LIGHTING_BINDINGS  // r32ui image: depth-test-passing fragments per pixel

#endif
