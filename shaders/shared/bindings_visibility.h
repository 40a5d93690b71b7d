// Set 1 of the visibility raster (visibility.frag.glsl, engine/passes/visibility_pass.cpp). Its masked variants
// declare lighting.glsl's bindings through material.glsl (never used): the overdraw image comes after them.
#ifndef VISBUF_BINDINGS_VISIBILITY_H
#define VISBUF_BINDINGS_VISIBILITY_H

#include "bindings_lighting.h"

#define VISIBILITY_BINDING_OVERDRAW LIGHTING_BINDINGS  // r32ui image: depth-test-passing fragments per pixel

#endif
