#version 460
// Shading pass: one thread per pixel. ID -> draw -> object -> mesh level -> 3 indices -> 3 vertices,
// the same clip math as the visibility vertex shader, perspective-correct barycentrics with
// analytic derivatives, attribute interpolation, lighting. Background pixels are skipped (the
// colour image was cleared to the background before).
#extension GL_GOOGLE_include_directive : require
#include "lighting.glsl"
#include "shared/barycentrics.h"

layout(local_size_x = SHADE_TILE_X, local_size_y = SHADE_TILE_Y) in;
layout(std430, set = 0, binding = BINDING_INDICES) readonly buffer IndexBlock { uint indices[]; };
layout(std430, set = 0, binding = BINDING_DRAWS) readonly buffer DrawBlock { DrawCommand draws[]; };
layout(set = 0, binding = BINDING_VISIBILITY) uniform usampler2D visibility;
layout(set = 0, binding = BINDING_COLOR, rgba16f) uniform writeonly image2D colorOut;
#if WRITE_ATTRIBUTES
layout(std430, set = 0, binding = BINDING_ATTRIBUTES) writeonly buffer AttributeBlock { float attributes[]; };

// The reconstruction itself, for the stress suite's double-precision comparison (config.h: layout).
void writeAttributes(ivec2 p, ObjectData o, Vertex v0, Vertex v1, Vertex v2, Barycentrics b, vec3 normal) {
  vec3 l = b.lambda;
  vec3 pos = l.x * objectToCamera(o, vertexPosition(v0)) + l.y * objectToCamera(o, vertexPosition(v1)) +
             l.z * objectToCamera(o, vertexPosition(v2));
  vec4 clip = frame.viewProj * vec4(pos, 1.0);
  vec2 uv = l.x * vec2(v0.u, v0.v) + l.y * vec2(v1.u, v1.v) + l.z * vec2(v2.u, v2.v);
  float a[ATTRIBUTE_FLOATS] = float[](pos.x, pos.y, pos.z, clip.z / clip.w, normal.x, normal.y, normal.z, 1.0,
                                      uv.x, uv.y, l.y, l.z, b.ddx.y, b.ddy.y, b.ddx.z, b.ddy.z);
  uint base = (uint(p.y) * uint(frame.viewport.x) + uint(p.x)) * ATTRIBUTE_FLOATS;
  for (int i = 0; i < ATTRIBUTE_FLOATS; ++i) attributes[base + uint(i)] = a[i];
}
#endif

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= int(frame.viewport.x) || p.y >= int(frame.viewport.y)) return;
  uvec2 raw = texelFetch(visibility, p, 0).xy;
  if (raw.x == VIS_NOTHING) return;
  uint slot, tri;
  if (frame.wideIds != 0u) {
    slot = raw.x - 1u;
    tri = raw.y;
  } else {
    uint v = raw.x - 1u;
    slot = v >> frame.triangleBits;
    tri = v & ((1u << frame.triangleBits) - 1u);
  }
  DrawCommand d = draws[slot];
  ObjectData o = objectAt(d.firstInstance);
  uint base = d.firstIndex + 3u * tri;
  Vertex v0 = vertexAt(indices[base + 0u] + uint(d.vertexOffset));
  Vertex v1 = vertexAt(indices[base + 1u] + uint(d.vertexOffset));
  Vertex v2 = vertexAt(indices[base + 2u] + uint(d.vertexOffset));
  vec4 c0 = clipPosition(o, vertexPosition(v0));
  vec4 c1 = clipPosition(o, vertexPosition(v1));
  vec4 c2 = clipPosition(o, vertexPosition(v2));
  vec2 ndc = (vec2(p) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
  Barycentrics b = computeBarycentrics(c0, c1, c2, ndc, 2.0 * frame.viewport.zw);
  vec3 l = b.lambda;

  vec3 n = l.x * octDecode(v0.normal) + l.y * octDecode(v1.normal) + l.z * octDecode(v2.normal);
  vec3 normal = normalize(normalToWorld(o, n));
  vec4 vc = l.x * unpackColor(v0.color) + l.y * unpackColor(v1.color) + l.z * unpackColor(v2.color);
  vec3 position = l.x * objectToCamera(o, vertexPosition(v0)) + l.y * objectToCamera(o, vertexPosition(v1)) +
                  l.z * objectToCamera(o, vertexPosition(v2));
  imageStore(colorOut, p, vec4(shadeSurface(factorSurface(o.materialIndex, position, normal, vc), uvec2(p)), 1.0));
#if WRITE_ATTRIBUTES
  writeAttributes(p, o, v0, v1, v2, b, normal);
#endif
}
