// Set 1 bindings of the lights as lighting.glsl reads them: the same numbers in the own set of every pass that
// lights with shadeSurface() (shade, classify, forward, transparent, G-buffer lighting); each of those passes lists
// them in its set layout and numbers its other bindings from LIGHTING_BINDINGS on.
#ifndef VISBUF_BINDINGS_LIGHTING_H
#define VISBUF_BINDINGS_LIGHTING_H

#define LIGHTING_BINDING_LIGHTS 0       // PointLightData[FrameData.pointLightCount]
#define LIGHTING_BINDING_LIGHT_TILES 1  // uint[]: the light culling's tile lists (config.h LIGHT_TILE_*)
#define LIGHTING_BINDINGS 2

#endif
