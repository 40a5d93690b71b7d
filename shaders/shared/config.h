// Limits and constants shared by C++ and GLSL. Magnitudes are given for the 1M-object stress scene.
#ifndef VISBUF_CONFIG_H
#define VISBUF_CONFIG_H

// Workgroup size of the culling pass: one thread per object.
#define CULL_WORKGROUP_SIZE 64
// Shading pass tile (one thread per pixel).
#define SHADE_TILE_X 8
#define SHADE_TILE_Y 8

// Maximum LOD levels per mesh. A halving chain from 30k triangles reaches ~30 after 10 levels.
#define MAX_LODS 12

// Reserved visibility value: nothing drawn at this pixel. Encoded IDs are (slot << triBits | tri) + 1.
#define VIS_NOTHING 0u

// Cull modes (FrameData.cullMode).
#define CULL_NONE 0u
#define CULL_FRUSTUM 1u

// Counter indices in the cull statistics buffer (uint each, read back every frame).
#define STAT_DRAW_COUNT 0          // draws appended (may exceed capacity: then overflow)
#define STAT_OBJECTS_TESTED 1
#define STAT_FRUSTUM_CULLED 2
#define STAT_TRIANGLES_DRAWN 3     // triangles in the draws that fit the capacity
#define STAT_DRAW_OVERFLOW 4       // draws dropped because drawCapacity was exceeded
#define STAT_LOD_HISTOGRAM 8       // MAX_LODS counters: draws per LOD level
#define STAT_COUNT (STAT_LOD_HISTOGRAM + MAX_LODS)

// Descriptor bindings (set 0) used by every pass; one layout keeps the frame script simple.
#define BINDING_FRAME 0      // uniform FrameData
#define BINDING_OBJECTS 1    // ObjectData[]
#define BINDING_MESHES 2     // MeshData[]
#define BINDING_VERTICES 3   // Vertex[] (unified vertex pool)
#define BINDING_INDICES 4    // uint[] (unified index pool)
#define BINDING_DRAWS 5      // DrawCommand[] written by cull
#define BINDING_STATS 6      // uint[STAT_COUNT]
#define BINDING_MATERIALS 7  // MaterialData[]
#define BINDING_VISIBILITY 8 // usampler/uimage visibility target (r32ui or rg32ui)
#define BINDING_COLOR 9      // rgba16f output image

#endif
