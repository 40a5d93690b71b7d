// Material evaluation shared by every path: glTF metallic-roughness with its five texture slots, sampled with
// explicit screen-space gradients (the shading pass passes its analytic barycentric derivatives, the raster
// paths dFdx/dFdy), so mip selection is the same function of the same quantities on every path.
//
// Sampling is done in the shader from texelFetch (sampleTexture): lavapipe has no dynamic indexing of
// sampled-image arrays (shaderSampledImageArrayDynamicIndexing = 0), so the texture class can only be chosen by a
// switch over constant indices, and one image may be used with several glTF samplers. Filtering in the shader
// gives every glTF sampler state (wrap S/T, nearest/linear, mip none/nearest/linear) from one image binding per
// class, with the LOD formula of the Vulkan spec (rho = max of the gradient lengths in texels, lambda = log2 rho).
#ifndef VISBUF_MATERIAL_GLSL
#define VISBUF_MATERIAL_GLSL

#include "lighting.glsl"

// 0: the untextured variant of a material shader (shaders/CMakeLists.txt), without any sampling code.
#ifndef VB_TEXTURED
#define VB_TEXTURED 1
#endif

layout(set = 0, binding = SCENE_BINDING_TEXTURE_CLASSES) uniform texture2DArray textureClasses[MAX_TEXTURE_CLASSES];
// The scene's texture class count (gpu::Specialization): the sampling code of the classes beyond it is removed
// when the pipeline is compiled (all of it for an untextured scene).
layout(constant_id = 1) const uint VB_TEXTURE_CLASSES = MAX_TEXTURE_CLASSES;

// What a path knows about the surface at a pixel, before the material is applied.
struct SurfaceInputs {
  vec3 position;         // camera-relative world position
  vec3 normal;           // interpolated world normal (not normalised)
  vec4 tangent;          // interpolated world tangent xyz, w: bitangent sign; w == 0: none (derived per pixel)
  vec3 dpdx, dpdy;       // screen derivatives of position (per pixel)
  vec2 uv0, uv1;         // TEXCOORD_0/1
  vec2 duv0dx, duv0dy;   // their screen derivatives (per pixel)
  vec2 duv1dx, duv1dy;
  vec4 color;            // COLOR_0 (white without)
  bool frontFacing;
};

int wrapTexel(int i, int n, uint mode) {
  if (mode == 1u) return clamp(i, 0, n - 1);  // ClampToEdge
  if (mode == 2u) {                           // MirroredRepeat
    int t = i - 2 * n * int(floor(float(i) / float(2 * n)));
    return t < n ? t : 2 * n - 1 - t;
  }
  return i - n * int(floor(float(i) / float(n)));  // Repeat
}

// One mip level, nearest or bilinear.
vec4 sampleLevel(texture2DArray t, int layer, vec2 uv, int level, bool linear, uint wrapS, uint wrapT) {
  // Level sizes from level 0 (square powers of two): textureSize() with a level that differs between lanes is
  // not reliable on lavapipe.
  ivec2 size = max(textureSize(t, 0).xy >> level, ivec2(1));
  if (!linear) {
    ivec2 i = ivec2(floor(uv * vec2(size)));
    return texelFetch(t, ivec3(wrapTexel(i.x, size.x, wrapS), wrapTexel(i.y, size.y, wrapT), layer), level);
  }
  vec2 f = uv * vec2(size) - 0.5;
  ivec2 i0 = ivec2(floor(f));
  vec2 a = f - vec2(i0);
  int x0 = wrapTexel(i0.x, size.x, wrapS), x1 = wrapTexel(i0.x + 1, size.x, wrapS);
  int y0 = wrapTexel(i0.y, size.y, wrapT), y1 = wrapTexel(i0.y + 1, size.y, wrapT);
  vec4 t00 = texelFetch(t, ivec3(x0, y0, layer), level), t10 = texelFetch(t, ivec3(x1, y0, layer), level);
  vec4 t01 = texelFetch(t, ivec3(x0, y1, layer), level), t11 = texelFetch(t, ivec3(x1, y1, layer), level);
  return mix(mix(t00, t10, a.x), mix(t01, t11, a.x), a.y);
}

// The level of detail of the Vulkan spec (isotropic): lambda = log2(max(|duv/dx|, |duv/dy|) * size).
float mipLambda(vec2 duvdx, vec2 duvdy, float size) {
  float rho = max(length(duvdx), length(duvdy)) * size;
  return rho > 0.0 ? log2(rho) : -128.0;
}

// Samples `t` (one size class) at layer `layer` with the glTF sampler `bits` and explicit gradients.
vec4 sampleClass(texture2DArray t, int layer, uint bits, vec2 uv, vec2 duvdx, vec2 duvdy) {
  uint wrapS = (bits >> TEXTURE_SAMPLER_WRAP_S_SHIFT) & 3u, wrapT = (bits >> TEXTURE_SAMPLER_WRAP_T_SHIFT) & 3u;
  uint mip = (bits >> TEXTURE_SAMPLER_MIP_SHIFT) & 3u;
  int levels = textureQueryLevels(t);
  float lambda = mipLambda(duvdx, duvdy, float(textureSize(t, 0).x));
  if (lambda <= 0.0) return sampleLevel(t, layer, uv, 0, (bits & TEXTURE_SAMPLER_MAG_LINEAR) != 0u, wrapS, wrapT);
  bool linear = (bits & TEXTURE_SAMPLER_MIN_LINEAR) != 0u;
  float maxLevel = float(levels - 1);
  lambda = min(lambda, maxLevel);
  if (mip == 0u) return sampleLevel(t, layer, uv, 0, linear, wrapS, wrapT);
  if (mip == 1u) return sampleLevel(t, layer, uv, int(min(ceil(lambda + 0.5) - 1.0, maxLevel)), linear, wrapS, wrapT);
  int l0 = int(floor(lambda));
  float f = lambda - float(l0);
  vec4 a = sampleLevel(t, layer, uv, l0, linear, wrapS, wrapT);
  if (f == 0.0 || l0 + 1 >= levels) return a;
  return mix(a, sampleLevel(t, layer, uv, l0 + 1, linear, wrapS, wrapT), f);
}

#define VB_CLASS_CASE(k)                                                     \
  case k:                                                                    \
    if (k < VB_TEXTURE_CLASSES)                                              \
      return sampleClass(textureClasses[k], layer, bits, uv, duvdx, duvdy); \
    break;

// Samples a baked image (class << 16 | layer): the class is chosen by constant index (see the top).
vec4 sampleImage(uint image, uint bits, vec2 uv, vec2 duvdx, vec2 duvdy) {
  int layer = int(image & 0xffffu);
  switch (image >> 16) {
    VB_CLASS_CASE(0) VB_CLASS_CASE(1) VB_CLASS_CASE(2) VB_CLASS_CASE(3) VB_CLASS_CASE(4) VB_CLASS_CASE(5)
    VB_CLASS_CASE(6) VB_CLASS_CASE(7) VB_CLASS_CASE(8) VB_CLASS_CASE(9) VB_CLASS_CASE(10) VB_CLASS_CASE(11)
    VB_CLASS_CASE(12) VB_CLASS_CASE(13) VB_CLASS_CASE(14) VB_CLASS_CASE(15) VB_CLASS_CASE(16) VB_CLASS_CASE(17)
    VB_CLASS_CASE(18) VB_CLASS_CASE(19) VB_CLASS_CASE(20) VB_CLASS_CASE(21) VB_CLASS_CASE(22) VB_CLASS_CASE(23)
  }
  return vec4(1.0);
}
#undef VB_CLASS_CASE

// A material's texture slot at the pixel: its TEXCOORD set, KHR_texture_transform (applied to the gradients
// too), the sample. White where the slot has no texture.
vec4 sampleSlot(TextureSlotData slot, SurfaceInputs si) {
#if !VB_TEXTURED
  return vec4(1.0);
#else
  if (VB_TEXTURE_CLASSES == 0u || slot.image == TEXTURE_NONE) return vec4(1.0);
  bool second = ((slot.samplerBits >> TEXTURE_SAMPLER_TEXCOORD_SHIFT) & 0xffu) == 1u;
  vec2 uv = second ? si.uv1 : si.uv0;
  vec2 dx = second ? si.duv1dx : si.duv0dx, dy = second ? si.duv1dy : si.duv0dy;
  mat2 m = mat2(slot.transform01.xy, slot.transform01.zw);
  return sampleImage(slot.image, slot.samplerBits, m * uv + slot.transform2.xy, m * dx, m * dy);
#endif
}

// Alpha of a material at the pixel (base colour factor x texture x vertex colour), for MASK and BLEND.
float materialAlpha(uint materialIndex, SurfaceInputs si) {
  MaterialData m = materialAt(materialIndex);
  return m.baseColor.a * si.color.a * sampleSlot(m.textures[TEXTURE_SLOT_BASE_COLOR], si).a;
}

// The tangent frame's tangent and bitangent at the pixel: the mesh's tangents when it has them, else derived
// from the position and uv derivatives of the normal texture's TEXCOORD set (dP/du, dP/dv by solving the 2x2
// system; the bitangent sign follows the uv orientation, so mirrored uvs work). False when the uvs do not vary.
bool tangentFrame(SurfaceInputs si, vec3 n, bool secondSet, out vec3 t, out vec3 b) {
  if (si.tangent.w != 0.0) {
    t = si.tangent.xyz - n * dot(n, si.tangent.xyz);
    if (dot(t, t) <= 0.0) return false;
    t = normalize(t);
    b = cross(n, t) * (si.tangent.w < 0.0 ? -1.0 : 1.0);
    return true;
  }
  vec2 dx = secondSet ? si.duv1dx : si.duv0dx, dy = secondSet ? si.duv1dy : si.duv0dy;
  float det = dx.x * dy.y - dx.y * dy.x;
  if (abs(det) <= 1e-20) return false;
  vec3 dpdu = (dy.y * si.dpdx - dx.y * si.dpdy) / det;
  vec3 dpdv = (dx.x * si.dpdy - dy.x * si.dpdx) / det;
  t = dpdu - n * dot(n, dpdu);
  if (dot(t, t) <= 0.0) return false;
  t = normalize(t);
  b = cross(n, t) * (dot(cross(n, t), dpdv) < 0.0 ? -1.0 : 1.0);
  return true;
}

// The unit normal of a normal-mapped slot (TEXTURE_SLOT_NORMAL, TEXTURE_SLOT_CLEARCOAT_NORMAL) at the pixel: texel
// (the slot's sample) in the tangent frame of unit geometric normal n, its xy times `scale`; side -1 flips the whole
// frame (back faces of double-sided materials). side * n where the slot has no texture or the frame is degenerate.
vec3 mappedNormal(SurfaceInputs si, vec3 n, float side, TextureSlotData ns, vec4 texel, float scale) {
  if (VB_TEXTURED == 0 || VB_TEXTURE_CLASSES == 0u || ns.image == TEXTURE_NONE) return side * n;
  vec3 t, b;
  bool second = ((ns.samplerBits >> TEXTURE_SAMPLER_TEXCOORD_SHIFT) & 0xffu) == 1u;
  if (!tangentFrame(si, n, second, t, b)) return side * n;
  vec3 tn = texel.xyz * 2.0 - 1.0;
  // A two-channel (BC5) normal map stores x and y of a unit vector: z is rebuilt before the normal scale.
  if ((ns.samplerBits & TEXTURE_SAMPLER_TWO_CHANNEL) != 0u) tn.z = sqrt(max(0.0, 1.0 - tn.x * tn.x - tn.y * tn.y));
  tn.xy *= scale;
  vec3 mapped = side * (t * tn.x + b * tn.y + n * tn.z);
  return dot(mapped, mapped) > 0.0 ? normalize(mapped) : side * n;
}

Surface evaluateMaterial(uint materialIndex, SurfaceInputs si) {
  MaterialData m = materialAt(materialIndex);
  vec3 n = normalize(si.normal);
  // Back faces of double-sided materials: the whole tangent frame flips (as the glTF sample viewer does).
  float side = !si.frontFacing && (m.flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u ? -1.0 : 1.0;
  // Every slot's texel in one loop whose bound is read from the material: the sampling code (a switch over the
  // texture classes) is then compiled once, not once per slot (lavapipe's compile time).
  vec4 texel[TEXTURE_SLOTS];
  for (int slot = 0; slot < TEXTURE_SLOTS; ++slot) texel[slot] = vec4(1.0);
#if VB_TEXTURED
  for (uint slot = 0u; slot < m.slotCount; ++slot) texel[slot] = sampleSlot(m.textures[slot], si);
#endif
  vec4 base = m.baseColor * si.color * texel[TEXTURE_SLOT_BASE_COLOR];
  Surface s = plainSurface(si.position, side * n, base.rgb);
  s.alpha = base.a;
  if ((VB_MATERIAL_FEATURES & MATERIAL_FEATURE_UNLIT) != 0u && (m.flags & MATERIAL_FLAG_UNLIT) != 0u) {
    s.unlit = true;  // (nothing else of the material is read)
    return s;
  }
  vec4 mr = texel[TEXTURE_SLOT_METALLIC_ROUGHNESS];
  s.metallic = clamp(m.params.x * mr.b, 0.0, 1.0);
  s.roughness = clamp(m.params.y * mr.g, 0.0, 1.0);
  // (untextured variants: no occlusion texture, and no fetch of its slot per pixel)
  if (VB_TEXTURED != 0 && m.textures[TEXTURE_SLOT_OCCLUSION].image != TEXTURE_NONE)
    s.occlusion = 1.0 + m.params.z * (texel[TEXTURE_SLOT_OCCLUSION].r - 1.0);
  s.emissive = m.emissive.rgb * texel[TEXTURE_SLOT_EMISSIVE].rgb;
  s.normal = mappedNormal(si, n, side, m.textures[TEXTURE_SLOT_NORMAL], texel[TEXTURE_SLOT_NORMAL], m.emissive.w);
  if ((VB_MATERIAL_FEATURES & MATERIAL_FEATURE_CLEARCOAT) != 0u && (m.flags & MATERIAL_FLAG_CLEARCOAT) != 0u) {
    s.clearcoat = clamp(m.clearcoat * texel[TEXTURE_SLOT_CLEARCOAT].r, 0.0, 1.0);
    s.clearcoatRoughness = clamp(m.clearcoatRoughness * texel[TEXTURE_SLOT_CLEARCOAT_ROUGHNESS].g, 0.0, 1.0);
    TextureSlotData cn = m.textures[TEXTURE_SLOT_CLEARCOAT_NORMAL];
    s.clearcoatNormal = mappedNormal(si, n, side, cn, texel[TEXTURE_SLOT_CLEARCOAT_NORMAL], cn.scale);
  }
  return s;
}

#endif
