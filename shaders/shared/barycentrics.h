// Perspective-correct barycentrics with analytic screen-space derivatives, after Schied &
// Dachsbacher, "Deferred Attribute Interpolation for Memory-Efficient Deferred Shading" (HPG 2015).
// Compiled as GLSL (shade pass) and as C++ with GLM (unit tests compare it with a double reference).
//
// Inputs: clip-space positions of the triangle's vertices, the pixel centre in NDC, and the size of
// one pixel in NDC (2/width, 2/height). Output: lambda (sums to 1) and d(lambda)/dx, d(lambda)/dy
// per pixel. Screen-space barycentrics s_i are linear in NDC with constant gradients g_i; the
// perspective-correct ones are lambda_i = (s_i / w_i) / sum_j (s_j / w_j), whose derivatives follow
// from the quotient rule exactly (no finite differences).
#ifndef VISBUF_BARYCENTRICS_H
#define VISBUF_BARYCENTRICS_H

#ifdef __cplusplus
namespace visbuf::gpu {
using vec2 = glm::vec2;
using vec3 = glm::vec3;
#define VB_INLINE inline
#else
#define VB_INLINE
#endif

struct Barycentrics {
  vec3 lambda;
  vec3 ddx;  // per pixel step in +x
  vec3 ddy;  // per pixel step in +y
};

VB_INLINE Barycentrics computeBarycentrics(vec4 c0, vec4 c1, vec4 c2, vec2 ndc, vec2 pixelNdc) {
  vec3 invW = 1.0f / vec3(c0.w, c1.w, c2.w);
  vec2 p0 = vec2(c0.x, c0.y) * invW.x;
  vec2 p1 = vec2(c1.x, c1.y) * invW.y;
  vec2 p2 = vec2(c2.x, c2.y) * invW.z;
  float invArea = 1.0f / ((p1.x - p0.x) * (p2.y - p0.y) - (p2.x - p0.x) * (p1.y - p0.y));
  vec3 gx = vec3(p1.y - p2.y, p2.y - p0.y, p0.y - p1.y) * invArea;  // d s_i / d ndc.x
  vec3 gy = vec3(p2.x - p1.x, p0.x - p2.x, p1.x - p0.x) * invArea;  // d s_i / d ndc.y
  vec2 d = ndc - p0;
  vec3 s = vec3(1.0f, 0.0f, 0.0f) + gx * d.x + gy * d.y;
  vec3 f = s * invW;
  float sumF = f.x + f.y + f.z;
  vec3 fx = gx * invW;
  vec3 fy = gy * invW;
  float sumFx = fx.x + fx.y + fx.z;
  float sumFy = fy.x + fy.y + fy.z;
  float invSum = 1.0f / sumF;
  Barycentrics b;
  b.lambda = f * invSum;
  b.ddx = (fx - b.lambda * sumFx) * (invSum * pixelNdc.x);
  b.ddy = (fy - b.lambda * sumFy) * (invSum * pixelNdc.y);
  return b;
}

#ifdef __cplusplus
}  // namespace visbuf::gpu
#endif
#undef VB_INLINE

#endif
