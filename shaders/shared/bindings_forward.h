// Set 1 of the forward pass (forward.frag.glsl, engine/passes/forward_pass.cpp): lighting.glsl's, then its own.
#ifndef VISBUF_BINDINGS_FORWARD_H
#define VISBUF_BINDINGS_FORWARD_H

#include "bindings_lighting.h"

#define FORWARD_BINDING_OVERDRAW LIGHTING_BINDINGS  // r32ui image: depth-test-passing fragments per pixel

#endif
