// Set 1 of the tiled light culling (light_cull.comp.glsl, engine/passes/light_cull_pass.cpp).
#ifndef VISBUF_BINDINGS_LIGHT_CULL_H
#define VISBUF_BINDINGS_LIGHT_CULL_H

#define LIGHT_CULL_BINDING_LIGHTS 0  // PointLightData[FrameData.pointLightCount]
#define LIGHT_CULL_BINDING_TILES 1   // uint[]: LIGHT_TILE_HEADER counters, then per tile a count + LIGHTS_PER_TILE indices
#define LIGHT_CULL_BINDING_DEPTH 2   // sampler2D (sampler2DMS with MSAA): the visibility depth, per-tile depth bounds

#endif
