// Limits and constants shared by C++ and GLSL. Magnitudes are given for the 1M-object stress scene.
#ifndef VISBUF_CONFIG_H
#define VISBUF_CONFIG_H

// Workgroup size of the culling pass: one thread per object.
#define CULL_WORKGROUP_SIZE 64
// Shading pass tile (one thread per pixel).
#define SHADE_TILE_X 8
#define SHADE_TILE_Y 8

// Maximum LOD levels per mesh. Halving steps down to 2048 triangles, then steps of 0.7 (MeshBuildOptions): the
// Kitten (28,944 triangles) reaches 10 triangles in 13 levels.
#define MAX_LODS 16

// Reserved visibility value: nothing drawn at this pixel. Encoded IDs are (slot << triBits | tri) + 1.
#define VIS_NOTHING 0u

// Multisampled visibility and forward targets: 1 (off), 2 or 4 samples per pixel at the standard sample
// locations (Vulkan spec, "Multisampling"), where the device supports them for every target format.
#define MAX_MSAA_SAMPLES 4

// Cull modes (FrameData.cullMode).
#define CULL_NONE 0u
#define CULL_FRUSTUM 1u
#define CULL_OCCLUSION 2u  // two phases: last frame's visible set, depth pyramid, then the rest

// Cull phases (push constant): single-phase modes use CULL_PHASE_EARLY only.
#define CULL_PHASE_EARLY 0u
#define CULL_PHASE_LATE 1u
// The late phase runs in two dispatches: every object gets the pyramid test at the level whose texels span its
// rectangle in 2x2; those it does not prove occluded, where a finer level exists, are listed and tested again by
// the second dispatch (PassConstants.variant = CULL_REFINE), one thread per listed object, three levels finer.
#define CULL_REFINE 1u
// Cluster culling: the cull pass lists the objects it would draw whole with the hardware raster whose LOD has
// clusters (LodData.firstCluster), and a dispatch over that list (PassConstants.variant = CULL_CLUSTERS, one
// workgroup per listed object) tests each cluster -- CLUSTER_TRIANGLES consecutive triangles of the LOD -- against
// the frustum, its back-face cone and, in the late phase, the depth pyramid, and appends one draw per run of
// consecutive surviving clusters (to the micro-raster: one per small cluster).
#define CULL_CLUSTERS 2u
// The late phase of occlusion culling first sieves every object through the frustum alone (cull_sieve.comp: a
// culled object's history is cleared and counted) and lists the rest; the late cull proper then runs over that list
// (PassConstants.variant = CULL_LATE_LISTED, indirect). lavapipe runs every branch of the cull under a lane mask,
// so without the sieve an object outside the frustum cost as much as one tested against the pyramid.
#define CULL_LATE_LISTED 3u
// Early cluster occlusion: the early phase's cluster dispatch also tests each cluster against the pyramid that the
// previous frame left (FrameData.earlyClusterOcclusion; a guess: the camera and the objects may have moved since),
// and defers the ones it hides instead of drawing them: each is listed (object ID, LOD << 24 | cluster) and one late
// cluster draw is reserved for it. After the late phase's pyramid is built, a dispatch over that list
// (PassConstants.variant = CULL_CLUSTER_RETEST, one thread per entry) tests each against it and draws the ones it
// does not hide, so that a wrong guess costs time, never a pixel: the early phase draws every object of last frame's
// visible set, with its clusters that the old pyramid does not hide.
#define CULL_CLUSTER_RETEST 4u
// The late phase's occlusion test (cull_occlusion.comp, variants CULL_LATE_LISTED and CULL_REFINE) decides
// visibility only and lists the objects to draw late (visible now, not drawn early: LATE_DRAW_LIST_WORD); the late
// draw dispatch (cull.comp, PassConstants.variant = CULL_LATE_DRAW, indirect) selects their LOD and routes them.
#define CULL_LATE_DRAW 5u
#define SIEVE_OBJECTS_PER_THREAD 8u  // cull_sieve.comp: one atomic per subgroup for this many objects per lane
#define CLUSTER_TRIANGLES 64u
// Only objects whose screen box exceeds this many pixels per side (or that reach the near plane) are drawn as
// clusters: a smaller one would pay a draw per cluster for the few triangles its cones and pyramid could remove.
#define CLUSTER_MIN_PIXELS 64.0
#define CLUSTER_NONE 0xffffffffu

// Depth pyramid: at most 2^15 pixels per side (16 levels incl. the full-resolution level 0).
#define MAX_PYRAMID_LEVELS 16
// The pyramid is built in few dispatches (depth_pyramid.comp.glsl): each thread reduces a 2^PYRAMID_REDUCTIONS square
// of its dispatch's source level through PYRAMID_REDUCTIONS levels on its own (8x8 -> 4x4 -> 2x2 -> 1).
#define PYRAMID_TILE 8
#define PYRAMID_REDUCTIONS 3
#define PYRAMID_DISPATCH_LEVELS (PYRAMID_REDUCTIONS + 1)  // storage images per dispatch: slot j = source level + j
// The occlusion tests read level 1 (2x2 pixels a texel) and coarser, never level 0: the pyramid then does not copy
// the full-resolution depth (a quarter of its cost on lavapipe) unless level 0 is read back (--view pyramid).
#define PYRAMID_FIRST_TESTED_LEVEL 1

// Counter indices in the cull statistics buffer (uint each, read back every frame).
#define STAT_DRAW_COUNT 0          // draws appended (may exceed capacity: then overflow)
#define STAT_OBJECTS_TESTED 1
#define STAT_FRUSTUM_CULLED 2
#define STAT_TRIANGLES_DRAWN 3     // triangles in the draws that fit the capacity
#define STAT_DRAW_OVERFLOW 4       // draws dropped because drawCapacity was exceeded (both phases)
#define STAT_DRAW_COUNT_LATE 5     // draws appended by the late phase (occlusion mode)
#define STAT_OCCLUSION_CULLED 6    // late phase: rejected by the depth pyramid
#define STAT_SUBPIXEL_CULLED 7     // late phase: bounds cover no pixel centre
#define STAT_LOD_HISTOGRAM 8       // MAX_LODS counters: draws per LOD level
#define STAT_LIST_DRAWS (STAT_LOD_HISTOGRAM + MAX_LODS)  // 2 x DRAW_LISTS: draws appended to list l in phase p
                                                         // at [p * DRAW_LISTS + l] (the indirect draw counts)
// MSAA frames (FrameData.msaaSamples > 1): pixels whose samples carry more than one ID (or some nothing), which
// the shading pass shades once per distinct ID (shaders/msaa_samples.glsl). Reset by the shading pass itself.
#define STAT_PER_SAMPLE_PIXELS (STAT_LIST_DRAWS + 2 * DRAW_LISTS)
// Software micro-raster (FrameData.swRaster): draws routed to sw_raster.comp instead of the hardware raster, per
// phase and draw list at [p * DRAW_LISTS + l] (they fill their list's region from its end), and their triangles;
// triangles whose box exceeded SW_RASTER_MAX_EXTENT pixels (never, while the cull pass's size bound holds:
// counted, never silent).
#define STAT_SW_DRAWS (STAT_PER_SAMPLE_PIXELS + 1)
#define STAT_SW_TRIANGLES (STAT_SW_DRAWS + 2 * DRAW_LISTS)
#define STAT_SW_OVERSIZE (STAT_SW_TRIANGLES + 1)
// Late phase's refinement dispatch (CULL_REFINE): objects it tested again at the finer level, and those it found
// occluded there (also counted in STAT_OCCLUSION_CULLED).
#define STAT_REFINE_TESTED (STAT_SW_OVERSIZE + 1)
#define STAT_REFINE_OCCLUDED (STAT_REFINE_TESTED + 1)
// Visbuf shading, single-sampled: the pixels it shaded (pixels whose ID shows something), reset by the shading pass.
#define STAT_COVERED_PIXELS (STAT_REFINE_OCCLUDED + 1)
// Cluster culling (CULL_CLUSTERS): objects expanded into clusters, clusters tested, culled by the frustum, by their
// back-face cone and by the depth pyramid (or covering no pixel centre), the draws appended for them (also in
// STAT_LIST_DRAWS / STAT_SW_DRAWS) and, per phase and draw list at [p * DRAW_LISTS + l], the cluster draws
// reserved (objects whose reservation does not fit the list's cluster reserve are drawn whole).
#define STAT_CLUSTER_OBJECTS (STAT_COVERED_PIXELS + 1)
#define STAT_CLUSTERS_TESTED (STAT_CLUSTER_OBJECTS + 1)
#define STAT_CLUSTERS_FRUSTUM (STAT_CLUSTERS_TESTED + 1)
#define STAT_CLUSTERS_BACKFACING (STAT_CLUSTERS_FRUSTUM + 1)
#define STAT_CLUSTERS_OCCLUDED (STAT_CLUSTERS_BACKFACING + 1)
#define STAT_CLUSTER_DRAWS (STAT_CLUSTERS_OCCLUDED + 1)
// Early cluster occlusion (FrameData.earlyClusterOcclusion): the early phase's clusters that last frame's pyramid
// hid, deferred to the late phase's retest (CULL_CLUSTER_RETEST), and those of them the retest drew.
#define STAT_CLUSTERS_DEFERRED (STAT_CLUSTER_DRAWS + 1)
#define STAT_CLUSTERS_RECOVERED (STAT_CLUSTERS_DEFERRED + 1)
#define STAT_CLUSTER_RESERVED (STAT_CLUSTERS_RECOVERED + 1)
#define STAT_COUNT (STAT_CLUSTER_RESERVED + 2 * DRAW_LISTS)
// After the counters (same buffer, not read back): per cull phase, the micro-raster's indirect dispatch (x, 1, 1)
// and its merge's indirect draw (vertexCount, 1, 0, 0), written by the cull pass where it routes a draw there and
// left at 0 otherwise: a phase without micro-raster draws runs neither (SW_ARGS_UINTS per phase).
#define SW_ARGS STAT_COUNT
#define SW_ARGS_UINTS 8u
#define SW_ARGS_DISPATCH 0u
#define SW_ARGS_MERGE 3u
#define SW_RASTER_MAX_WORKGROUPS 1024u
// Then, per cull phase, the cluster list's header: its entry count and the cluster dispatch's indirect arguments
// (x, 1, 1; x at most CLUSTER_MAX_WORKGROUPS, the workgroups stride over the list). The entries (object ID, LOD)
// are in the visible-list buffer after the refinement list: the early phase's from its start, the late phase's
// from its end (an object is drawn in one phase at most, so objectCount entries hold both).
#define CLUSTER_ARGS (SW_ARGS + 2 * SW_ARGS_UINTS)
#define CLUSTER_ARGS_UINTS 4u
#define CLUSTER_MAX_WORKGROUPS 4096u
// Then the retest list's header (CULL_CLUSTER_RETEST): its entry count and the retest dispatch's indirect arguments
// (x, 1, 1; x at most CLUSTER_MAX_WORKGROUPS, the workgroups stride over the list). Its entries are in the
// visible-list buffer (RETEST_LIST_WORD).
#define RETEST_ARGS (CLUSTER_ARGS + 2 * CLUSTER_ARGS_UINTS)
#define STAT_BUFFER_UINTS (RETEST_ARGS + 4u)

// Draw lists: the cull pass routes each object, by its material and winding, into the list of the raster
// state it needs. Each list is a region of the draw buffer per phase with its own count (STAT_LIST_DRAWS) and
// capacity; a list with no objects in the scene has capacity 0 and is never recorded. BLEND objects are in no
// list (the transparency pass draws them); ObjectData.flags holds each object's list (objectDrawList). FLIPPED:
// negative-determinant transforms, front faces clockwise.
#define DRAW_LIST_OPAQUE 0
#define DRAW_LIST_OPAQUE_FLIPPED 1
#define DRAW_LIST_OPAQUE_DOUBLE_SIDED 2  // no face culling
#define DRAW_LIST_MASKED 3               // alpha-tested (discard below the cutoff)
#define DRAW_LIST_MASKED_FLIPPED 4
#define DRAW_LIST_MASKED_DOUBLE_SIDED 5
#define DRAW_LISTS 6
#define DRAW_LIST_NONE 0xffffffffu

// Skinning pass (shaders/skin.comp.glsl): its own descriptor set, one thread per instance vertex.
#define SKIN_WORKGROUP_SIZE 64
#define SKIN_BINDING_VERTICES 0      // Vertex[] (the unified pool: the rest vertices)
#define SKIN_BINDING_MESHES 1        // MeshData[] (instance slots: region addresses; bounds, LOD errors per pose)
#define SKIN_BINDING_SKIN_VERTICES 2 // SkinVertex[] (joints, weights)
#define SKIN_BINDING_JOINTS 3        // vec4[3 * joints]: joint matrix rows, skin space, per instance
#define SKIN_BINDING_INSTANCES 4     // SkinInstance[]
#define SKIN_BINDING_VERTICES_1 5    // vertex windows 1..3 (as SCENE_BINDING_VERTICES_1..3)
#define SKIN_BINDING_VERTICES_2 6
#define SKIN_BINDING_VERTICES_3 7
#define SKIN_BINDING_EXTRAS 8        // VertexExtra[] (rest tangents)
#define SKIN_BINDING_BOUNDS 9        // uint[SKIN_BOUNDS_UINTS] per instance (GPU bounds only; else a placeholder)
#define SKIN_BINDING_MORPH_DELTAS 10 // MorphDelta[] of the morph-target meshes (else a placeholder)
// GPU-computed skinned bounds (RendererConfig::skinBounds = Gpu): per instance the ordered-float encodings
// (orderedFloat in skin.comp.glsl) of min x, y, z and of min -x, -y, -z over its skinned vertices, then of
// min -|p - centre|, reduced with atomicMin only (so one fill of 0xffffffff resets them); the skin_bounds
// variant turns them into the mesh slot's sphere in three steps (PassConstants.variant). 32 bytes per instance.
#define SKIN_BOUNDS_UINTS 8
#define SKIN_BOUNDS_CENTRE 0u    // per instance: AABB centre -> boundsSphere.xyz
#define SKIN_BOUNDS_DISTANCE 1u  // per instance vertex: largest distance from the centre
#define SKIN_BOUNDS_RADIUS 2u    // per instance: -> boundsSphere.w
// PassConstants.material (third word) of the skinning pass: bit 0 set = GPU bounds (reduce the AABB; the resolve variant writes
// the sphere), clear = the CPU's joint-reach sphere (SkinInstance.bounds) goes to the mesh slot.
#define SKIN_MODE_GPU_BOUNDS 1u

// Set 0 of every frame pass: the scene set (engine/render/scene_descriptors.cpp), one per frame slot, with the
// frame's uniforms and the scene data nearly every pass reads. Set 1 is each pass's own (its shaders/shared/
// bindings_*.h).
#define SCENE_BINDING_FRAME 0         // uniform FrameData (the frame slot's)
#define SCENE_BINDING_OBJECTS 1       // ObjectData[]
#define SCENE_BINDING_OBJECTS_HIGH 2  // ObjectData[] from FrameData.objectSplit on (one descriptor range is capped by
                                      // maxStorageBufferRange: 2M objects on lavapipe)
#define SCENE_BINDING_MESHES 3        // MeshData[]
// The vertex pool is read through VERTEX_WINDOWS descriptor windows of 2^FrameData.vertexWindowShift vertices
// (each window at most maxStorageBufferRange): SCENE_BINDING_VERTICES, then _1.._3.
#define VERTEX_WINDOWS 4
#define SCENE_BINDING_VERTICES 4      // Vertex[] (unified vertex pool)
#define SCENE_BINDING_VERTICES_1 5
#define SCENE_BINDING_VERTICES_2 6
#define SCENE_BINDING_VERTICES_3 7
#define SCENE_BINDING_INDICES 8       // uint[] (unified index pool)
#define SCENE_BINDING_MATERIALS 9     // MaterialData[]
#define SCENE_BINDING_VERTEX_EXTRAS 10  // VertexExtra[] (tangent, TEXCOORD_1) of meshes that have them
#define SCENE_BINDING_TEXTURE_CLASSES 11  // texture2DArray[MAX_TEXTURE_CLASSES]
// Uniform texel buffer views of the vertex pool (RGBA32UI: two texels per Vertex), the index pool (RGB32UI: one
// texel per triangle; a level starts at a multiple of 3) and the object records (RGBA32UI: four texels per
// ObjectData), read where VB_TEXELS is 1 (GpuScene::texels).
#define SCENE_BINDING_VERTEX_TEXELS 12
#define SCENE_BINDING_TRIANGLE_TEXELS 13
#define SCENE_BINDING_OBJECT_TEXELS 14
#define SCENE_BINDING_MESH_TEXELS 15      // the MeshData records, RGBA32UI (3 + MAX_LODS texels each)
#define SCENE_BINDING_MATERIAL_TEXELS 16  // the MaterialData records, RGBA32UI
#define SCENE_BINDING_TRIANGLE_PLANES 17  // vec4 per triangle of the index pool (GpuScene::trianglePlanes), RGBA32F
#define SCENE_BINDING_STATS 18            // uint[STAT_COUNT]: the frame-wide counters (then SW_ARGS)

// The cull pass's visible list: the visible set of its history as a list, for the next frame's early cull (one
// thread per listed object instead of one per object of the scene): VISIBLE_LIST_HEADER uints -- count, then the
// early cull's indirect dispatch (x, 1, 1) --, then the object IDs in append order. Written by the late cull, reset
// before it. The late phase's refinement list (CULL_REFINE) follows it in the same buffer, at word
// VISIBLE_LIST_HEADER + objectCount, in the same layout. Then the cluster lists' (object, LOD) entries (2 x
// objectCount words), then the late phase's list of the objects inside the frustum (CULL_LATE_LISTED), same layout,
// then the retest list and the late draw list.
#define VISIBLE_LIST_HEADER 4u
#define LATE_LIST_WORD(objectCount) (2u * (VISIBLE_LIST_HEADER + (objectCount)) + 2u * (objectCount))
// After the late list: the retest list's entries (2 words each: object ID, LOD << 24 | cluster; RETEST_ARGS holds its
// count), room for RETEST_CAPACITY of them. A cluster that finds no room is drawn in the early phase.
#define RETEST_LIST_WORD(objectCount) (LATE_LIST_WORD(objectCount) + VISIBLE_LIST_HEADER + (objectCount))
#define RETEST_CAPACITY(objectCount) ((objectCount) + 65536u)
#define RETEST_NONE 0xFFFFFFFFu  // an entry whose cluster was drawn early after all (no late draw left to reserve)
// After the retest list's room: the late draw list (CULL_LATE_DRAW), in the visible list's layout.
#define LATE_DRAW_LIST_WORD(objectCount) (RETEST_LIST_WORD(objectCount) + 2u * RETEST_CAPACITY(objectCount))

// Materials (types.h MaterialData). Flags: the glTF alpha mode and double-sidedness.
#define MATERIAL_FLAG_MASK 1u          // alphaMode MASK: alpha < params.w is cut out
#define MATERIAL_FLAG_BLEND 2u         // alphaMode BLEND: drawn by the transparency pass
#define MATERIAL_FLAG_DOUBLE_SIDED 4u  // no back-face culling; back faces shade with the flipped normal
#define MATERIAL_FLAG_UNLIT 8u         // KHR_materials_unlit: the base colour is the pixel's colour
#define MATERIAL_FLAG_CLEARCOAT 16u    // KHR_materials_clearcoat with a weight > 0
// Shading features beyond the metallic-roughness core (scene.h materialFeatures): specialisation constant 6
// (common.glsl VB_MATERIAL_FEATURES) holds those a pipeline may meet, so code for the others is removed: the
// scene's union for the single-dispatch paths, one material's for each classified dispatch.
#define MATERIAL_FEATURE_UNLIT 1u
#define MATERIAL_FEATURE_CLEARCOAT 2u
#define MATERIAL_FEATURES_ALL 3u
#define TEXTURE_SLOTS 8  // base colour, metallic-roughness, normal, occlusion, emissive, clearcoat (3)
#define TEXTURE_SLOT_BASE_COLOR 0
#define TEXTURE_SLOT_METALLIC_ROUGHNESS 1
#define TEXTURE_SLOT_NORMAL 2
#define TEXTURE_SLOT_OCCLUSION 3
#define TEXTURE_SLOT_EMISSIVE 4
#define TEXTURE_SLOT_CLEARCOAT 5            // R: coat weight
#define TEXTURE_SLOT_CLEARCOAT_ROUGHNESS 6  // G: coat roughness
#define TEXTURE_SLOT_CLEARCOAT_NORMAL 7     // the coat's tangent-space normal
#define TEXTURE_NONE 0xffffffffu
// TextureSlotData.samplerBits: wrap S (2 bits) and T (2 bits) as scene/texture.h WrapMode, magnification
// linear, minification linear, mip filter (2 bits, MipFilter), TEXCOORD set (8 bits), two-channel image.
#define TEXTURE_SAMPLER_WRAP_S_SHIFT 0
#define TEXTURE_SAMPLER_WRAP_T_SHIFT 2
#define TEXTURE_SAMPLER_MAG_LINEAR 16u
#define TEXTURE_SAMPLER_MIN_LINEAR 32u
#define TEXTURE_SAMPLER_MIP_SHIFT 6
#define TEXTURE_SAMPLER_TEXCOORD_SHIFT 8
// The image holds two channels (a BC5 class: x, y of a normal map); the normal slot rebuilds z from them.
#define TEXTURE_SAMPLER_TWO_CHANNEL 65536u
// Baked textures: one texture2DArray per size class (scene/texture.h), bound as a fixed array of
// MAX_TEXTURE_CLASSES (12 sizes x 2 colour spaces); unused entries hold a 1x1 placeholder. Lavapipe has no
// dynamic indexing of sampled-image arrays, so shaders index it with constants only (material.glsl).
#define MAX_TEXTURE_CLASSES 24
#define EXTRA_NONE 0xffffffffu      // MeshData.extraOffset of a mesh without VertexExtra records
// The draw lists' buffer (cull and micro-raster passes): uvec4[2 * DRAW_LISTS]; [l]: x first slot (early phase),
// y first slot (late), z capacity, w 1 if the software micro-raster may take this list's draws (opaque, uncapped);
// [DRAW_LISTS + l]: x the draws of its region reserved for clusters (the capacity beyond one draw per object).
// Software micro-raster (sw_raster_pass): workgroup size (one workgroup per draw at a time), the largest triangle
// box it rasterises (pixels per side; its fixed-point edge functions stay within 32 bits up to there).
#define SW_RASTER_WORKGROUP 64
#define SW_RASTER_CHUNK 256  // triangles per back-face pre-pass (sw_raster.comp.glsl), queued in shared memory
#define SW_RASTER_MAX_EXTENT 96
// The most triangles of a draw it takes: one invocation rasterises a whole draw, and lavapipe's JIT stops any loop
// after 65,535 iterations (gallivm's loop limiter): a 28,800-triangle draw lost its last ~7,000 triangles.
#define SW_RASTER_MAX_TRIANGLES 2048u
// G-buffer baseline (gbuffer_pass, gbuffer_lighting_pass): the raster's attribute targets, read back by the
// lighting pass with texelFetch (constant indices only: lavapipe has no dynamic sampled-image indexing).
#define GBUFFER_TARGETS 5       // base colour + alpha, octahedral normal, metallic/roughness/occlusion/unlit, emissive, coat
// Lights: shaders/shared/bindings_lighting.h, light_cull.comp.glsl.
// PointLightData.type (engine/scene/light.h LightType): KHR_lights_punctual point, spot, directional.
#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u
// Ambient radiance of the uniform environment every surface sees (scaled by occlusion; lighting.glsl).
#define AMBIENT_RADIANCE 0.15
// Tiled light culling: 16x16-pixel tiles, each with a fixed-capacity list of the point lights whose sphere of
// influence overlaps the tile's frustum between its nearest and farthest covered depth. 1080p: 120x68 tiles
// x 257 uints = 8.4 MB. Lights beyond the capacity are dropped from that tile and counted, never silently.
#define LIGHT_TILE_SIZE 16
#define LIGHTS_PER_TILE 256
#define LIGHT_TILE_STRIDE (LIGHTS_PER_TILE + 1)
#define LIGHT_TILE_HEADER 4       // uints before the first tile:
#define LIGHT_STAT_OVERFLOW_TILES 0   // tiles whose list overflowed
#define LIGHT_STAT_DROPPED 1          // (tile, light) pairs dropped for lack of capacity
#define LIGHT_STAT_MAX_PER_TILE 2     // the longest list before clamping
#define LIGHT_STAT_PAIRS 3            // (tile, light) pairs kept

// Material classification (classify_pass, classify.comp.glsl, classify_scan.comp.glsl): the shading tiles
// (SHADE_TILE_X x SHADE_TILE_Y pixels) are listed per material present in them, and each material is shaded by its
// own indirect dispatch over its list (a tile with k materials is in k lists; a material without pixels gets 0
// workgroups). The material tiles: CLASSIFY_HEADER uints, then MaterialTiles (types.h) per material, whose
// first three words are the VkDispatchIndirectCommand. The tile list: one uint per (tile, material) pair, tile x
// in the low 16 bits, y in the high 16 (at most 2048 tiles a side at 16384 pixels), grouped by material. Its
// capacity, tiles x min(materials, tile pixels), can never overflow; 1080p with >= 64 materials: 8.3 MB.
#define CLASSIFY_HEADER 8              // uints before the first MaterialTiles record:
#define CLASSIFY_STAT_PAIRS 0          // (tile, material) pairs listed (the scan's total)
#define CLASSIFY_STAT_MATERIALS 1      // materials with at least one pixel
#define CLASSIFY_SCAN_WORKGROUP 256    // the prefix sum: one workgroup, CLASSIFY_SCAN_WORKGROUP materials a step
#define CLASSIFY_NO_MATERIAL 0xffffffffu
// Workgroups per row of a material's shading dispatch. Vulkan guarantees only 65,535 workgroups in x, and one
// material can cover more tiles (a 4K frame has 129,600); rows of 128 fit the largest frame (2048^2 tiles) in
// 32,768 rows.
#define CLASSIFY_DISPATCH_WIDTH 128u
// Covered-pixel shading: the buffer's header (VkDispatchIndirectCommand of the shading dispatch, then the pixel
// count); the shading dispatch takes SHADE_TILE_X x SHADE_TILE_Y listed pixels per workgroup, its workgroups in rows
// of CLASSIFY_DISPATCH_WIDTH, as the classified one.
#define COVERED_PIXELS_HEADER 4u
#define COVERED_TILES_WORKGROUP 64u  // covered_pixels.comp: shading tiles per workgroup (one thread lists a tile)
// A listed pixel (x | y << 16, x below 16,384) with this bit set is one where the micro-raster drew and was not
// merged into the ID target (FramePlan::swResolved): the shading takes the nearer of its fragment and the target's.
#define COVERED_PIXEL_MICRO_RASTER 0x8000u

// Per-pixel attribute record written by the shade_attributes variant (FrameOptions::readAttributes):
//  0..2 camera-relative world position, 3 depth (reverse-Z NDC), 4..6 unit world normal, 7 = 1 (written),
//  8..9 TEXCOORD_0, 10..11 lambda1, lambda2, 12..13 d(lambda1)/dx,dy, 14..15 d(lambda2)/dx,dy (per pixel).
#define ATTRIBUTE_FLOATS 16

#endif
