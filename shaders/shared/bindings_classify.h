// Set 1 of the material classification (classify.comp.glsl, classify_scan.comp.glsl and the CLASSIFIED variant of
// shade.comp.glsl; engine/passes/classify_pass.cpp): the shading pass's bindings, then the classification buffers
// (layout: config.h CLASSIFY_*).
#ifndef VISBUF_BINDINGS_CLASSIFY_H
#define VISBUF_BINDINGS_CLASSIFY_H

#include "bindings_shade.h"

#define CLASSIFY_BINDING_MATERIAL_TILES (SHADE_BINDING_COVERED_TEXELS + 1)    // CLASSIFY_HEADER uints + MaterialTiles[]
#define CLASSIFY_BINDING_TILE_LIST (SHADE_BINDING_COVERED_TEXELS + 2)          // uint per (tile, material) pair

#endif
