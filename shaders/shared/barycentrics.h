// Perspective-correct barycentrics with analytic screen-space derivatives, after Schied &
// Dachsbacher, "Deferred Attribute Interpolation for Memory-Efficient Deferred Shading" (HPG 2015).
// Compiled as GLSL (shade pass) and as C++ with GLM (unit tests compare it with a double reference).
//
// Inputs: clip-space positions of the triangle's vertices, the pixel centre in NDC, and the size of
// one pixel in NDC (2/width, 2/height). Output: lambda (sums to 1) and d(lambda)/dx, d(lambda)/dy
// per pixel. Screen-space barycentrics s_i are linear in NDC (edge functions e_i, any common scale);
// the perspective-correct ones are lambda_i = (e_i / w_i) / sum_j (e_j / w_j), whose derivatives follow
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
  // Vertices relative to the pixel centre, so every edge function below is a small cross product of
  // nearby values (no 1 - s0 - s1 cancellation, no division by the triangle's area: the screen-space
  // weights only need to be proportional, and slivers stay accurate).
  vec2 p0 = vec2(c0.x, c0.y) * invW.x - ndc;
  vec2 p1 = vec2(c1.x, c1.y) * invW.y - ndc;
  vec2 p2 = vec2(c2.x, c2.y) * invW.z - ndc;
  // e_i: twice the signed area of (pixel, p_{i+1}, p_{i+2}), proportional to the screen-space weight s_i.
  vec3 e = vec3(p1.x * p2.y - p2.x * p1.y, p2.x * p0.y - p0.x * p2.y, p0.x * p1.y - p1.x * p0.y);
  vec3 ex = vec3(p1.y - p2.y, p2.y - p0.y, p0.y - p1.y);  // d e_i / d ndc.x
  vec3 ey = vec3(p2.x - p1.x, p0.x - p2.x, p1.x - p0.x);  // d e_i / d ndc.y
  vec3 f = e * invW;
  vec3 fx = ex * invW;
  vec3 fy = ey * invW;
  float sumF = f.x + f.y + f.z;
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
