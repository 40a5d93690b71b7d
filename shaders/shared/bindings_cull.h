// Set 1 of the cull pass (cull.comp.glsl, engine/passes/cull_pass.cpp).
#ifndef VISBUF_BINDINGS_CULL_H
#define VISBUF_BINDINGS_CULL_H

#define CULL_BINDING_DRAWS 0         // DrawCommand[] (written)
#define CULL_BINDING_HISTORY 1       // uint[] per object: 1 if visible at the end of the last frame
#define CULL_BINDING_VISIBLE_LIST 2  // the visible set listed (config.h VISIBLE_LIST_HEADER)
#define CULL_BINDING_DRAW_LISTS 3    // uvec4[DRAW_LISTS] (config.h DRAW_LIST_*)
#define CULL_BINDING_PYRAMID 4       // sampler2D depth pyramid (r32f, all levels; reverse-Z: min = farthest)
#define CULL_BINDING_CLUSTERS 5      // ClusterData[] (LodData.firstCluster)

#endif
