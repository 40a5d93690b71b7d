#version 460
// Shading pass: one thread per pixel. ID -> draw -> object -> mesh level -> 3 indices -> 3 vertices,
// the same clip math as the visibility vertex shader, perspective-correct barycentrics with
// analytic derivatives, attribute interpolation, lighting. Background pixels are skipped (the
// colour image was cleared to the background before). MSAA variant: msaa_samples.glsl.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_samplerless_texture_functions : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "material.glsl"
#include "uniform_branch.glsl"
#include "shared/barycentrics.h"
#include "visibility_id.glsl"
#include "shared/bindings_classify.h"

layout(local_size_x = SHADE_TILE_X, local_size_y = SHADE_TILE_Y) in;
#if MSAA
#include "msaa_samples.glsl"  // multisampled IDs: shadeMultisampledPixel() per pixel, shadeVisible() per ID
#else
layout(set = 1, binding = SHADE_BINDING_COLOR, rgba16f) uniform writeonly image2D colorOut;
layout(std430, set = 0, binding = SCENE_BINDING_STATS) buffer ShadeStatsBlock { uint stats[]; };  // STAT_COVERED_PIXELS
#endif
#if CLASSIFIED
// Classified shading (classify_pass): one indirect dispatch per material, one workgroup per tile of its list; the
// lanes whose pixel shows another material leave, and the material index is uniform over the dispatch.
layout(push_constant) uniform Push { PassConstants pc; };
layout(std430, set = 1, binding = CLASSIFY_BINDING_MATERIAL_TILES) readonly buffer MaterialTileBlock {
  uint header[CLASSIFY_HEADER];
  MaterialTiles materialTiles[];
};
layout(std430, set = 1, binding = CLASSIFY_BINDING_TILE_LIST) readonly buffer TileListBlock { uint tileList[]; };
#endif
#if COVERED  // (buffer references: common.glsl)
layout(buffer_reference, std430, buffer_reference_align = 4) readonly buffer CoveredPixelList { uint words[]; };
layout(set = 1, binding = SHADE_BINDING_COVERED_TEXELS) uniform usamplerBuffer coveredTexels;
// Word i of the covered-pixel list: through its texel view where VB_TEXELS (on lavapipe a buffer-reference read is a
// scalar load per lane, about 4.6 ms a read per pixel at 100k kittens; a texel, one load for the batch).
uint coveredWord(uint i) {
  if (VB_TEXELS != 0u) return texelFetch(coveredTexels, int(i)).x;
  return CoveredPixelList(uvec2(frame.coveredPixelsLow, frame.coveredPixelsHigh)).words[i];
}
#endif
#if WRITE_ATTRIBUTES
layout(std430, set = 1, binding = SHADE_BINDING_ATTRIBUTES) writeonly buffer AttributeBlock { float attributes[]; };

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

// The face the rasteriser saw, as forward.frag's gl_FrontFacing (counter-clockwise on screen) and the object's
// winding: the sign of the determinant of the clip positions' (x, y, w), valid for triangles crossing w = 0 too
// (Olano & Greer, "Triangle Scan Conversion using 2D Homogeneous Coordinates", 1997).
bool frontFacing(ObjectData o, vec4 c0, vec4 c1, vec4 c2) {
  bool ccw = determinant(mat3(c0.xyw, c1.xyw, c2.xyw)) < 0.0;
  return ccw != ((o.flags & OBJECT_FLAG_FLIP_WINDING) != 0u);
}

// The lit colour of the surface with this raw ID (not VIS_NOTHING) at `at` inside pixel p (pixel units from its
// top-left corner; (0.5, 0.5): the centre). Derivatives are per pixel step.
vec3 shadeVisible(uvec2 raw, ivec2 p, vec2 at) {
  uint slot, tri;
  decodeVisibility(raw, slot, tri);
  uint firstIndex, vertexOffset, object;
  drawAt(slot, firstIndex, vertexOffset, object);
  ObjectData o = objectAt(object);
#if CLASSIFIED
  o.materialIndex = uniformBranch(pc.material);  // the value main() checked, known to be uniform over the dispatch
#endif
  uint base = firstIndex + 3u * tri;
  uvec3 local = triangleIndices(base);
  Vertex v0 = meshVertex(o.meshIndex, local.x + vertexOffset);
  Vertex v1 = meshVertex(o.meshIndex, local.y + vertexOffset);
  Vertex v2 = meshVertex(o.meshIndex, local.z + vertexOffset);
  vec4 c0 = clipPosition(o, vertexPosition(v0));
  vec4 c1 = clipPosition(o, vertexPosition(v1));
  vec4 c2 = clipPosition(o, vertexPosition(v2));
  vec2 ndc = (vec2(p) + at) * frame.viewport.zw * 2.0 - 1.0;
  Barycentrics b = computeBarycentrics(c0, c1, c2, ndc, 2.0 * frame.viewport.zw);
  vec3 l = b.lambda;

  vec3 n = l.x * octDecode(v0.normal) + l.y * octDecode(v1.normal) + l.z * octDecode(v2.normal);
  vec3 normal = normalize(normalToWorld(o, n));
  vec3 p0 = objectToCamera(o, vertexPosition(v0)), p1 = objectToCamera(o, vertexPosition(v1)),
       p2 = objectToCamera(o, vertexPosition(v2));
  SurfaceInputs si;
  si.position = l.x * p0 + l.y * p1 + l.z * p2;
  si.normal = normal;
  si.dpdx = b.ddx.x * p0 + b.ddx.y * p1 + b.ddx.z * p2;
  si.dpdy = b.ddy.x * p0 + b.ddy.y * p1 + b.ddy.z * p2;
  mat3x2 uv0 = mat3x2(vec2(v0.u, v0.v), vec2(v1.u, v1.v), vec2(v2.u, v2.v));
  si.uv0 = uv0 * l;
  si.duv0dx = uv0 * b.ddx;
  si.duv0dy = uv0 * b.ddy;
  si.tangent = vec4(0.0);
  si.uv1 = vec2(0.0);
  si.duv1dx = vec2(0.0);
  si.duv1dy = vec2(0.0);
  uint extra = meshExtraOffset(o.meshIndex);
  if (VB_EXTRAS != 0u && extra != EXTRA_NONE) {
    VertexExtra e0 = vertexExtras[extra + local.x], e1 = vertexExtras[extra + local.y], e2 = vertexExtras[extra + local.z];
    mat3x2 uv1 = mat3x2(vec2(e0.u1, e0.v1), vec2(e1.u1, e1.v1), vec2(e2.u1, e2.v1));
    si.uv1 = uv1 * l;
    si.duv1dx = uv1 * b.ddx;
    si.duv1dy = uv1 * b.ddy;
    if (e0.tangentW != 0.0) {
      vec3 t = l.x * octDecode(meshTangent(o.meshIndex, local.x, e0)) +
               l.y * octDecode(meshTangent(o.meshIndex, local.y, e1)) +
               l.z * octDecode(meshTangent(o.meshIndex, local.z, e2));
      si.tangent = vec4(objectToCameraVector(o, t), e0.tangentW);  // mirrored instances: w flipped at import
    }
  }
  si.color = l.x * unpackColor(v0.color) + l.y * unpackColor(v1.color) + l.z * unpackColor(v2.color);
  si.frontFacing = frontFacing(o, c0, c1, c2);
  Surface s = evaluateMaterial(o.materialIndex, si);
#if WRITE_ATTRIBUTES
  writeAttributes(p, o, v0, v1, v2, b, normal);
#endif
  return shadeSurface(s, uvec2(p));
}

void main() {
#if CLASSIFIED
  uint entry = gl_WorkGroupID.y * CLASSIFY_DISPATCH_WIDTH + gl_WorkGroupID.x;  // (the last row may be partial)
  if (entry >= materialTiles[pc.material].tiles) return;
  uint tile = tileList[materialTiles[pc.material].first + entry];
  ivec2 p = ivec2(tile & 0xffffu, tile >> 16) * ivec2(SHADE_TILE_X, SHADE_TILE_Y) + ivec2(gl_LocalInvocationID.xy);
#elif COVERED
  // One thread per covered pixel (covered_pixels.comp listed them; workgroups in rows of CLASSIFY_DISPATCH_WIDTH).
  uint entry = (gl_WorkGroupID.y * CLASSIFY_DISPATCH_WIDTH + gl_WorkGroupID.x) * (SHADE_TILE_X * SHADE_TILE_Y) +
               gl_LocalInvocationIndex;
  if (entry >= coveredWord(3u)) return;
  uint pixel = coveredWord(COVERED_PIXELS_HEADER + entry);
  ivec2 p = ivec2(pixel & 0x7fffu, pixel >> 16);
#else
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
#endif
#if MSAA
  shadeMultisampledPixel(p);
#else
  if (p.x >= int(frame.viewport.x) || p.y >= int(frame.viewport.y)) return;
#if SW_RESOLVE && COVERED  // (the list says where the unmerged micro-raster drew)
  uvec2 raw = texelFetch(visibility, p, 0).xy;
  if ((pixel & COVERED_PIXEL_MICRO_RASTER) != 0u) raw = resolveMicroRaster(p, raw);
#elif SW_RESOLVE
  uvec2 raw = resolvedVisibility(p);
#else
  uvec2 raw = texelFetch(visibility, p, 0).xy;
#endif
  uint slot, tri;
  if (!decodeVisibility(raw, slot, tri)) return;
#if CLASSIFIED
  if (objectAt(drawObject(slot)).materialIndex != pc.material) return;
#endif
  imageStore(colorOut, p, vec4(shadeVisible(raw, p, vec2(0.5)), 1.0));
#if !COVERED  // (covered: every listed pixel is shaded, and covered_pixels.comp copies the list's count)
  uint shaded = subgroupAdd(1u);  // (over the lanes still here: the pixels shaded)
  if (subgroupElect()) atomicAdd(stats[STAT_COVERED_PIXELS], shaded);
#endif
#endif
}
