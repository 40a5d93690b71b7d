#version 460
// Software micro-raster (sw_raster_pass): the draws the cull pass routed here -- small objects, whose triangles
// cover a few pixels each -- are rasterised in compute instead of by the hardware raster (on lavapipe its
// geometry path is serial and costs ~130 ns per triangle, while compute runs on every core). Each subgroup takes
// one draw at a time, each lane a triangle: the same clip positions as the visibility vertex shader
// (clipPosition), the viewport transform, vertices snapped to 1/256 pixel, the draw list's face culling, pixel
// centres tested with integer edge functions under the top-left rule, depth from the plane of the positions the
// device's hardware raster interpolates (lavapipe: unsnapped; a GPU: snapped), and the nearest fragment kept per
// pixel by a 64-bit atomicMax of (reverse-Z depth bits << 32 | complemented payload). The merge (sw_merge.frag)
// then depth-tests those against the hardware raster's depth and writes the IDs and depth, so every
// later pass reads one visibility target.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "sw_payload.glsl"
#include "shared/bindings_sw_raster.h"

layout(local_size_x = SW_RASTER_WORKGROUP) in;
layout(std430, set = 1, binding = SW_RASTER_BINDING_DRAWS) readonly buffer DrawBlock { DrawCommand draws[]; };
layout(std430, set = 0, binding = SCENE_BINDING_STATS) buffer StatBlock { uint stats[]; };
layout(std430, set = 1, binding = SW_RASTER_BINDING_DRAW_LISTS) readonly buffer DrawListBlock { uvec4 drawLists[]; };
layout(std430, set = 1, binding = SW_RASTER_BINDING_VISIBILITY) buffer SwBlock { uint64_t swVisibility[]; };
layout(push_constant) uniform Push { PassConstants pc; };
#if SW_CPU
// Per subgroup: the chunk's front-facing triangles (SW_RASTER_CHUNK each; 4 lanes per subgroup at the least).
shared uint swQueue[SW_RASTER_WORKGROUP / 4 * SW_RASTER_CHUNK];

layout(set = 0, binding = SCENE_BINDING_TRIANGLE_PLANES) uniform samplerBuffer trianglePlanes;

// True where triangle t of the draw faces away from the camera by more than rounding could hide: the camera lies
// behind its object-space plane by more than 1e-3 of its distance (`reach` bounds that distance: the distance to
// the mesh's bounding sphere centre plus its radius), i.e. the cosine between the normal and the direction to the
// camera is below -1e-3. Front (counter-clockwise seen from outside) in object space is what both single-sided
// lists keep: a mirroring transform flips the screen winding and DRAW_LIST_OPAQUE_FLIPPED flips it back.
bool clearlyBackFacing(DrawCommand d, vec4 eye, float reach, uint t) {
  vec4 plane = texelFetch(trianglePlanes, int(d.firstIndex / 3u + t));
  return dot(plane.xyz, eye.xyz) + plane.w * eye.w < -1e-3 * reach;
}
#endif

// Window position in pixels relative to the pixel-centre grid (pixel (i, j)'s centre is (i, j)), unsnapped.
vec2 gridPosition(vec4 clip) {
  precise vec2 ndc = clip.xy / clip.w;  // (as the hardware's viewport transform: a division, not 1/w)
  precise vec2 half_ = 0.5 * frame.viewport.xy;
  precise vec2 window = ndc * half_ + half_;
  return window - 0.5;
}

#if SW_CPU
// lavapipe: reads the words at both ends of each pixel row of the draw's box (its bounding sphere's, capped at the
// micro-raster's extent) before the draw's atomics. On lavapipe each lane's 64-bit atomic is a locked
// compare-exchange in a loop over the lanes, and a locked instruction waits for the memory operations before it, so
// the first atomic on each cache line paid a whole miss, one after another (about a fifth of the micro-raster's time
// in a profile of the 1M-kitten field). Plain loads, one row per lane, miss together. The words read are not used;
// `refused` takes a bit that no stored word has (the depth bits of max(z, 0) >= 0, the clear is 0) so that the
// reads stay in the shader.
void warmPixels(ObjectData o, vec4 sphere, inout uint refused) {
  vec4 clip = clipPosition(o, sphere.xyz);
  if (!(clip.w > 0.0)) return;
  vec2 centre = gridPosition(clip);
  float radius = min(sphere.w * o.maxScale * frame.lodScale / clip.w, float(SW_RASTER_MAX_EXTENT));
  ivec2 last = ivec2(frame.viewport.xy) - 1;
  ivec2 lo = clamp(ivec2(centre - radius), ivec2(0), last), hi = clamp(ivec2(centre + radius), ivec2(0), last);
  uint width = uint(frame.viewport.x);
  uint64_t words = 0ul;
  for (int y = lo.y + int(gl_SubgroupInvocationID); y <= hi.y; y += int(gl_SubgroupSize))
    words |= swVisibility[uint(y) * width + uint(lo.x)] | swVisibility[uint(y) * width + uint(hi.x)];
  if ((words >> 63) != 0ul) refused += 1u;
}
#endif
// The same in 1/256 pixel (pixel (i, j)'s centre is (256 i, 256 j)): what coverage is decided on.
ivec2 snapToGrid(vec2 grid) { return ivec2(roundEven(grid * 256.0)); }

// Edge function of u -> v at p (positive inside a triangle of positive area).
int edge(ivec2 u, ivec2 v, ivec2 p) { return (v.x - u.x) * (p.y - u.y) - (v.y - u.y) * (p.x - u.x); }
// Top-left rule (y down, positive area): top edges run in +x, left edges in -y; other edges exclude their pixels.
int edgeBias(ivec2 u, ivec2 v) {
  ivec2 d = v - u;
  return (d.y < 0 || (d.y == 0 && d.x > 0)) ? 0 : -1;
}

// Returns 1 for a triangle it could not take (counted per draw: on lavapipe an atomic costs a loop over the lanes
// wherever it stands in the code, taken or not), else 0.
uint rasterTriangle(uint slot, DrawCommand d, ObjectData o, uint list, uint t) {
  uint base = d.firstIndex + 3u * t;
  uvec3 v = triangleIndices(base) + uint(d.vertexOffset);
  vec4 c0 = clipPosition(o, meshPosition(o.meshIndex, v.x));
  vec4 c1 = clipPosition(o, meshPosition(o.meshIndex, v.y));
  vec4 c2 = clipPosition(o, meshPosition(o.meshIndex, v.z));
  // The cull pass routes only objects wholly within the depth range (reverse-Z: 0 <= z_clip <= w_clip, beyond the near
  // plane and before a far plane); a frozen frame's camera may have moved since.
  if (!(c0.z <= c0.w && c1.z <= c1.w && c2.z <= c2.w && min(c0.z, min(c1.z, c2.z)) >= 0.0)) return 1u;
  vec2 g0 = gridPosition(c0), g1 = gridPosition(c1), g2 = gridPosition(c2);
  ivec2 p0 = snapToGrid(g0), p1 = snapToGrid(g1), p2 = snapToGrid(g2);
  ivec2 lo = min(p0, min(p1, p2)), hi = max(p0, max(p1, p2));
  ivec2 pxLo = max((lo + 255) >> 8, ivec2(0));
  ivec2 pxHi = min(hi >> 8, ivec2(frame.viewport.xy) - 1);
  if (pxLo.x > pxHi.x || pxLo.y > pxHi.y) return 0u;  // covers no pixel centre of the frame
  // Its edge functions could leave 32 bits: counted, never silent.
  if (hi.x - lo.x > SW_RASTER_MAX_EXTENT * 256 || hi.y - lo.y > SW_RASTER_MAX_EXTENT * 256) return 1u;
  // Work relative to p0 so that every product stays within 32 bits.
  ivec2 b = p1 - p0, c = p2 - p0, a = ivec2(0);
  int area = b.x * c.y - b.y * c.x;  // > 0: clockwise on screen (y down), a back face for VK_FRONT_FACE_CCW
  if (area == 0) return 0u;
  bool keep = list == DRAW_LIST_OPAQUE_DOUBLE_SIDED || (list == DRAW_LIST_OPAQUE_FLIPPED ? area > 0 : area < 0);
  if (!keep) return 0u;
  // Depth: the plane of z/w through the window positions, evaluated at the pixel centre, as the device's hardware
  // raster interpolates it, so that the two agree on which of two nearly coincident surfaces is nearer: llvmpipe
  // takes the plane of the unsnapped positions (the exact depth up to float rounding), NVIDIA's raster that of the
  // snapped ones. Measured against the hardware raster (SwRaster.MatchesHardwareRaster, 518,400 pixels): H100 1
  // pixel with the snapped plane, 21 with the unsnapped one; lavapipe 6 with the unsnapped plane. A triangle too
  // thin for a float plane keeps a constant depth: its nearest vertex's.
#if !SW_CPU
  g0 = vec2(p0) / 256.0;
  g1 = vec2(p1) / 256.0;
  g2 = vec2(p2) / 256.0;
#endif
  float z0 = c0.z / c0.w, z1 = c1.z / c1.w, z2 = c2.z / c2.w;
  precise vec2 e1 = g1 - g0, e2 = g2 - g0;
  precise float det = e1.x * e2.y - e1.y * e2.x;
  vec2 dz = vec2(0.0);
  float zAt0 = max(z0, max(z1, z2));  // reverse-Z: nearest
  if (det != 0.0 && (det > 0.0) == (area > 0)) {
    dz = vec2(z1 - z0, z2 - z0);
    dz = vec2(dz.x * e2.y - dz.y * e1.y, dz.y * e1.x - dz.x * e2.x) / det;
    zAt0 = z0;
  }
  if (area < 0) {  // same winding for the coverage test
    ivec2 s = b;
    b = c;
    c = s;
    area = -area;
  }
  int bias0 = edgeBias(b, c), bias1 = edgeBias(c, a), bias2 = edgeBias(a, b);
  uint payload = microRasterPayload(slot, t);
  // Equal depths keep the lowest payload, the first in draw order (lower slot, then lower triangle), as the
  // hardware raster's depth test keeps the first fragment: atomicMax over the payload's complement.
  uint rank = ~payload;
  uint width = uint(frame.viewport.x);
  // The box's pixel centres as one loop (on lavapipe a loop runs as often as its longest lane needs: one loop over
  // w * h candidates instead of rows times columns).
  int columns = pxHi.x - pxLo.x + 1, candidates = columns * (pxHi.y - pxLo.y + 1);
  ivec2 px = pxLo;
  for (int k = 0; k < candidates; ++k) {
    ivec2 p = px * 256 - p0;
    int w0 = edge(b, c, p), w1 = edge(c, a, p), w2 = edge(a, b, p);
    if (w0 + bias0 >= 0 && w1 + bias1 >= 0 && w2 + bias2 >= 0) {
      float z = zAt0 + dot(dz, vec2(px) - g0);
      uint64_t packed = (uint64_t(floatBitsToUint(max(z, 0.0))) << 32) | uint64_t(rank);
      uint i = uint(px.y) * width + uint(px.x);
#if !SW_CPU
      if (packed > swVisibility[i]) atomicMax(swVisibility[i], packed);  // (a GPU's atomics cost more than a load)
#else
      atomicMax(swVisibility[i], packed);  // (lavapipe: the load is another per-lane loop, the atomic one anyway)
#endif
    }
    px = px.x == pxHi.x ? ivec2(pxLo.x, px.y + 1) : ivec2(px.x + 1, px.y);
  }
  return 0u;
}

void main() {
  // This phase's routed draws of every list (each list's region filled from its end: slots
  // [first + capacity - count, first + capacity)), one draw per subgroup at a time, its triangles spread over the
  // subgroup's lanes: on lavapipe a subgroup is one SIMD batch that pays for its longest lane, so one draw per lane
  // made batches wait on their largest LOD (measured: 1.31 s against 1.07 s for this split, 200,000 kittens).
  uint c0 = drawLists[0].w != 0u ? min(stats[STAT_SW_DRAWS + pc.phase * DRAW_LISTS + 0u], drawLists[0].z) : 0u;
  uint c1 = drawLists[1].w != 0u ? min(stats[STAT_SW_DRAWS + pc.phase * DRAW_LISTS + 1u], drawLists[1].z) : 0u;
  uint c2 = drawLists[2].w != 0u ? min(stats[STAT_SW_DRAWS + pc.phase * DRAW_LISTS + 2u], drawLists[2].z) : 0u;
  uint total = c0 + c1 + c2;
#if SW_CPU
  // lavapipe: each workgroup takes a contiguous run of the list (in object order, which the loaded scene numbers
  // along a space-filling curve), so that a core's next draws touch the pixels its last ones warmed; the dispatch
  // is capped (SW_RASTER_MAX_WORKGROUPS) and a grid stride sent each workgroup's next draw elsewhere on the screen.
  uint perWorkgroup = (total + gl_NumWorkGroups.x - 1u) / gl_NumWorkGroups.x;
  uint begin = gl_WorkGroupID.x * perWorkgroup, end = min(begin + perWorkgroup, total);
  for (uint k = begin + gl_SubgroupID; k < end; k += gl_NumSubgroups) {
#else
  uint stride = gl_NumWorkGroups.x * gl_NumSubgroups;
  for (uint k = gl_WorkGroupID.x * gl_NumSubgroups + gl_SubgroupID; k < total; k += stride) {
#endif
    uint list = k < c0 ? 0u : k < c0 + c1 ? 1u : 2u;
    uint i = k - (list == 0u ? 0u : list == 1u ? c0 : c0 + c1);
    uvec4 region = drawLists[list];
    uint slot = (pc.phase == CULL_PHASE_LATE ? region.y : region.x) + region.z - 1u - i;
    DrawCommand d = draws[slot];
    ObjectData o = objectAt(d.firstInstance);
    uint triangles = d.indexCount / 3u;
    uint refused = 0u;
#if SW_CPU
    // lavapipe: back faces are dropped before their projection and setup. Per chunk of triangles each lane tests
    // one triangle's object-space plane against the camera (in object space, computed once per draw), the front
    // ones are queued in shared memory, and the raster runs over the queue only -- lavapipe executes every branch
    // for every lane of a batch, so skipping work takes fewer loop passes, not a branch. Only clear back faces are
    // dropped (a margin of 1e-3 of the cosine, where snapping could turn the projected winding); the raster's own
    // integer winding test decides the rest, as before. (On an H100 the queue cost more than it saved.)
    vec4 eye = eyeInObjectSpace(o);
    vec4 sphere = meshBoundsSphere(o.meshIndex);
    // (orthographic: eye.xyz is a direction, the plane test a cosine times its length)
    float reach = eye.w == 0.0 ? length(eye.xyz) : length(eye.xyz - sphere.xyz) + sphere.w;
    // (the planes are the rest pose's: a skinned or morphed instance's slot is not tested)
    bool cullBack = VB_TEXELS != 0u && list != DRAW_LIST_OPAQUE_DOUBLE_SIDED &&
                    (VB_SKINNED == 0u || uvec2(meshes[o.meshIndex].skinnedVertexLow,
                                               meshes[o.meshIndex].skinnedVertexHigh) == uvec2(0u));
    warmPixels(o, sphere, refused);
    uint queueBase = gl_SubgroupID * SW_RASTER_CHUNK;
    for (uint chunk = 0u; chunk < triangles; chunk += SW_RASTER_CHUNK) {
      uint chunkEnd = min(chunk + SW_RASTER_CHUNK, triangles);
      uint queued = 0u;
      for (uint t = chunk + gl_SubgroupInvocationID; t - gl_SubgroupInvocationID < chunkEnd; t += gl_SubgroupSize) {
        bool keep = t < chunkEnd && (!cullBack || !clearlyBackFacing(d, eye, reach, t));
        uvec4 ballot = subgroupBallot(keep);
        if (keep) swQueue[queueBase + queued + subgroupBallotExclusiveBitCount(ballot)] = t;
        queued += subgroupBallotBitCount(ballot);
      }
      subgroupBarrier();
      for (uint q = gl_SubgroupInvocationID; q - gl_SubgroupInvocationID < queued; q += gl_SubgroupSize)
        if (q < queued) refused += rasterTriangle(slot, d, o, list, swQueue[queueBase + q]);
      subgroupBarrier();
    }
#else
    for (uint t = gl_SubgroupInvocationID; t < triangles; t += gl_SubgroupSize)
      refused += rasterTriangle(slot, d, o, list, t);
#endif
    if (refused > 0u) atomicAdd(stats[STAT_SW_OVERSIZE], refused);
  }
}
