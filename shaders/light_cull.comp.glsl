#version 460
// Tiled light culling: one 16x16 workgroup per LIGHT_TILE_SIZE^2 screen tile. The tile's depth bounds are
// the nearest and farthest *covered* pixel of the visibility depth (background pixels are never shaded);
// every point light whose sphere of influence (its range, where the glTF window reaches zero) overlaps the
// tile's frustum between those bounds is appended to the tile's list, in ascending light index (a bit mask
// per chunk of 256 lights, compacted with popcounts), so the shading loop sums in the same order as the
// all-lights loop. Conservative: the side planes pass through the tile's pixel edges, and the radius and the
// depth bounds are widened by a relative 1e-4 (float rounding of the planes, the depth and the shading
// pass's reconstructed position). Lights beyond LIGHTS_PER_TILE are dropped and counted in the header.
#extension GL_GOOGLE_include_directive : require
#include "common.glsl"

layout(local_size_x = LIGHT_TILE_SIZE, local_size_y = LIGHT_TILE_SIZE) in;
layout(std430, set = 0, binding = BINDING_LIGHTS) readonly buffer PointLightBlock { PointLightData pointLights[]; };
layout(set = 0, binding = BINDING_LIGHT_DEPTH) uniform sampler2D sceneDepth;
layout(std430, set = 0, binding = BINDING_LIGHT_TILES) buffer LightTileOut { uint tilesOut[]; };

const uint kThreads = LIGHT_TILE_SIZE * LIGHT_TILE_SIZE;
shared uint depthMin, depthMax;  // float bits of positive depths order like the floats
shared uint chunkMask[kThreads / 32u];
shared uint listCount;

void main() {
  uint t = gl_LocalInvocationIndex;
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (t == 0u) {
    depthMin = 0xffffffffu;
    depthMax = 0u;
    listCount = 0u;
  }
  if (t < kThreads / 32u) chunkMask[t] = 0u;
  barrier();
  if (p.x < int(frame.viewport.x) && p.y < int(frame.viewport.y)) {
    float d = texelFetch(sceneDepth, p, 0).r;
    if (d > 0.0) {  // reverse-Z: 0 is the cleared background (infinitely far)
      atomicMin(depthMin, floatBitsToUint(d));
      atomicMax(depthMax, floatBitsToUint(d));
    }
  }
  barrier();
  uint tile = gl_WorkGroupID.y * frame.lightTilesX + gl_WorkGroupID.x;
  uint base = LIGHT_TILE_HEADER + tile * LIGHT_TILE_STRIDE;
  if (depthMax == 0u) {  // nothing covered: nothing shaded here
    if (t == 0u) tilesOut[base] = 0u;
    return;
  }
  // View distances (reverse-Z infinite: depth = near / distance), widened.
  float zNear = frame.nearPlane / uintBitsToFloat(depthMax) * (1.0 - 1e-4);
  float zFar = frame.nearPlane / uintBitsToFloat(depthMin) * (1.0 + 1e-4);
  // Side planes through the origin and the tile's pixel edges, in view space (x right, y up, looking down -z):
  // a point is inside when x/(-z) lies between the edges' ndc.x / projX (likewise y with projY < 0).
  vec2 lo = vec2(gl_WorkGroupID.xy * LIGHT_TILE_SIZE);
  vec2 hi = min(lo + float(LIGHT_TILE_SIZE), frame.viewport.xy);
  vec2 ndcLo = lo * frame.viewport.zw * 2.0 - 1.0, ndcHi = hi * frame.viewport.zw * 2.0 - 1.0;
  float x0 = ndcLo.x / frame.projX, x1 = ndcHi.x / frame.projX;
  float y0 = min(ndcLo.y / frame.projY, ndcHi.y / frame.projY), y1 = max(ndcLo.y / frame.projY, ndcHi.y / frame.projY);
  // Inward unit normals: x - x0 (-z) >= 0  ->  n = (1, 0, x0); -x + x1 (-z) >= 0  ->  n = (-1, 0, -x1).
  vec3 planes[4] = vec3[](normalize(vec3(1.0, 0.0, x0)), normalize(vec3(-1.0, 0.0, -x1)),
                          normalize(vec3(0.0, 1.0, y0)), normalize(vec3(0.0, -1.0, -y1)));

  for (uint chunk = 0u; chunk < frame.pointLightCount; chunk += kThreads) {
    uint i = chunk + t;
    bool inside = false;
    if (i < frame.pointLightCount) {
      PointLightData light = pointLights[i];
      float r = light.positionRange.w;
      if (r <= 0.0) {
        inside = true;  // infinite range
      } else {
        vec3 c = (frame.view * vec4(light.positionRange.xyz + frame.cameraOffset.xyz, 1.0)).xyz;
        float rr = r * (1.0 + 1e-4) + 1e-4 * (abs(c.x) + abs(c.y) + abs(c.z));
        inside = -c.z + rr >= zNear && -c.z - rr <= zFar;
        for (int k = 0; k < 4; ++k) inside = inside && dot(planes[k], c) >= -rr;
      }
      if (inside) atomicOr(chunkMask[t / 32u], 1u << (t % 32u));
    }
    barrier();
    if (inside) {
      uint slot = listCount + uint(bitCount(chunkMask[t / 32u] & ((1u << (t % 32u)) - 1u)));
      for (uint w = 0u; w < t / 32u; ++w) slot += uint(bitCount(chunkMask[w]));
      if (slot < LIGHTS_PER_TILE) tilesOut[base + 1u + slot] = i;
    }
    uint chunkCount = 0u;
    if (t == 0u)
      for (uint w = 0u; w < kThreads / 32u; ++w) chunkCount += uint(bitCount(chunkMask[w]));
    barrier();
    if (t == 0u) listCount += chunkCount;
    if (t < kThreads / 32u) chunkMask[t] = 0u;
    barrier();
  }
  if (t == 0u) {
    uint n = min(listCount, uint(LIGHTS_PER_TILE));
    tilesOut[base] = n;
    atomicAdd(tilesOut[LIGHT_STAT_PAIRS], n);
    atomicMax(tilesOut[LIGHT_STAT_MAX_PER_TILE], listCount);
    if (listCount > LIGHTS_PER_TILE) {
      atomicAdd(tilesOut[LIGHT_STAT_OVERFLOW_TILES], 1u);
      atomicAdd(tilesOut[LIGHT_STAT_DROPPED], listCount - LIGHTS_PER_TILE);
    }
  }
}
