#version 460
// Tiled light culling: one thread per LIGHT_TILE_SIZE^2 screen tile (8x8 tiles per workgroup). The thread
// takes the tile's depth bounds from the nearest and farthest *covered* pixel of the visibility depth
// (background pixels are never shaded), then walks every KHR_lights_punctual light in ascending index and
// appends those whose sphere of influence (its range, where the glTF window reaches zero) overlaps the tile's
// frustum between those bounds (directional lights and lights of infinite range: every covered tile), so the
// shading loop sums in the same order as the all-lights loop. Conservative: the side planes pass through the
// tile's pixel edges, and the radius and the depth bounds are widened by a relative 1e-4 (float rounding of
// the planes, the depth and the shading pass's reconstructed position). Lights beyond LIGHTS_PER_TILE are
// dropped and counted in the header.
//
// One thread per tile rather than one workgroup: on lavapipe a workgroup barrier costs microseconds (its
// invocations run as fibres), and a barrier-free serial walk vectorises across neighbouring tiles, which all
// test the same light at the same time (uniform loads).
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"
#include "shared/bindings_light_cull.h"

layout(local_size_x = 8, local_size_y = 8) in;
layout(std430, set = 1, binding = LIGHT_CULL_BINDING_LIGHTS) readonly buffer PointLightBlock { PointLightData pointLights[]; };
#if MSAA
layout(set = 1, binding = LIGHT_CULL_BINDING_DEPTH) uniform sampler2DMS sceneDepth;  // every sample is shaded: all count
#else
layout(set = 1, binding = LIGHT_CULL_BINDING_DEPTH) uniform sampler2D sceneDepth;
#endif
layout(std430, set = 1, binding = LIGHT_CULL_BINDING_TILES) buffer LightTileOut { uint tilesOut[]; };

void main() {
  uvec2 tileId = gl_GlobalInvocationID.xy;
  uint tilesY = (uint(frame.viewport.y) + LIGHT_TILE_SIZE - 1u) / LIGHT_TILE_SIZE;
  if (tileId.x >= frame.lightTilesX || tileId.y >= tilesY) return;
  uint base = LIGHT_TILE_HEADER + (tileId.y * frame.lightTilesX + tileId.x) * LIGHT_TILE_STRIDE;
  ivec2 lo = ivec2(tileId * LIGHT_TILE_SIZE);
  ivec2 hi = min(lo + LIGHT_TILE_SIZE, ivec2(frame.viewport.xy));
  float dMin = 1e30, dMax = 0.0;
  for (int y = lo.y; y < hi.y; ++y)
    for (int x = lo.x; x < hi.x; ++x) {
#if MSAA
      for (int s = 0; s < int(frame.msaaSamples); ++s) {
        float d = texelFetch(sceneDepth, ivec2(x, y), s).r;
#else
      {
        float d = texelFetch(sceneDepth, ivec2(x, y), 0).r;
#endif
        if (d > 0.0) {  // reverse-Z: 0 is the cleared background (infinitely far)
          dMin = min(dMin, d);
          dMax = max(dMax, d);
        }
      }
    }
  if (dMax == 0.0) {  // nothing covered: nothing shaded here
    tilesOut[base] = 0u;
    return;
  }
  // View distances (common.glsl's distanceOfDepth), widened (orthographic: also by an absolute 1e-5 of the far
  // distance, as a linear depth's rounding is absolute).
  float widen = orthographic() ? 1e-5 * frame.projection.w : 0.0;
  float zNear = distanceOfDepth(dMax) * (1.0 - 1e-4) - widen;
  float zFar = distanceOfDepth(dMin) * (1.0 + 1e-4) + widen;
  // Side planes through the tile's pixel edges, in view space (x right, y up, looking down -z). Perspective: through
  // the origin, a point is inside when x/(-z) lies between the edges' ndc.x / projX (likewise y with projY < 0);
  // orthographic: when x itself does.
  vec2 ndcLo = vec2(lo) * frame.viewport.zw * 2.0 - 1.0, ndcHi = vec2(hi) * frame.viewport.zw * 2.0 - 1.0;
  float x0 = ndcLo.x / frame.projX, x1 = ndcHi.x / frame.projX;
  float y0 = min(ndcLo.y / frame.projY, ndcHi.y / frame.projY), y1 = max(ndcLo.y / frame.projY, ndcHi.y / frame.projY);
  // Inward unit normals: x - x0 (-z) >= 0  ->  n = (1, 0, x0); -x + x1 (-z) >= 0  ->  n = (-1, 0, -x1); orthographic:
  // x - x0 >= 0 -> (1, 0, 0), offset -x0 (offsets 0 for perspective).
  float p = orthographic() ? 0.0 : 1.0, q = 1.0 - p;
  vec3 left = normalize(vec3(1.0, 0.0, p * x0)), right = normalize(vec3(-1.0, 0.0, -p * x1));
  vec3 bottom = normalize(vec3(0.0, 1.0, p * y0)), top = normalize(vec3(0.0, -1.0, -p * y1));
  vec4 offsets = q * vec4(-x0, x1, -y0, y1);  // (left, right, bottom, top)

  uint count = 0u;
  for (uint i = 0u; i < frame.pointLightCount; ++i) {
    vec4 pr = pointLights[i].positionRange;
    // Infinite range and directional lights: every tile. A spot light is culled by its range sphere, which
    // contains its cone.
    bool inside = pr.w <= 0.0 || pointLights[i].type == LIGHT_DIRECTIONAL;
    if (!inside) {
      vec3 c = (frame.view * vec4(pr.xyz + frame.cameraOffset.xyz, 1.0)).xyz;
      float r = pr.w * (1.0 + 1e-4) + 1e-4 * (abs(c.x) + abs(c.y) + abs(c.z));
      r += 1e-4 * (abs(offsets.x) + abs(offsets.y) + abs(offsets.z) + abs(offsets.w));  // (their rounding)
      inside = -c.z + r >= zNear && -c.z - r <= zFar && dot(left, c) + offsets.x >= -r &&
               dot(right, c) + offsets.y >= -r && dot(bottom, c) + offsets.z >= -r && dot(top, c) + offsets.w >= -r;
    }
    if (inside) {
      if (count < LIGHTS_PER_TILE) tilesOut[base + 1u + count] = i;
      ++count;
    }
  }
  uint n = min(count, uint(LIGHTS_PER_TILE));
  tilesOut[base] = n;
  atomicAdd(tilesOut[LIGHT_STAT_PAIRS], n);
  atomicMax(tilesOut[LIGHT_STAT_MAX_PER_TILE], count);
  if (count > LIGHTS_PER_TILE) {
    atomicAdd(tilesOut[LIGHT_STAT_OVERFLOW_TILES], 1u);
    atomicAdd(tilesOut[LIGHT_STAT_DROPPED], count - LIGHTS_PER_TILE);
  }
}
