// KHR_materials_pbrSpecularGlossiness -> glTF metallic-roughness, the conversion the importer applies to factors
// and the texture bake to texels (asset/spec_gloss_bake.cpp), so that every path shades one model.
//
// The spec-gloss model (extension spec): c_diff = diffuse.rgb x (1 - max(specular)), f0 = specular, roughness =
// 1 - glossiness. Metallic-roughness (lighting.glsl): c_diff = base x (1 - m), f0 = 0.04 (1 - m) + base x m. Six
// numbers cannot in general be matched by four, so the conversion is exact only where the spec-gloss surface is one
// metal-rough can show (a dielectric with f0 0.04, or a pure metal with no diffuse); elsewhere it picks m from the
// brightness (Rec. 601 luma of the linear colours' squares, sqrt(0.299 r^2 + 0.587 g^2 + 0.114 b^2)) of the two
// targets: m solves  d m = (s - 0.04 (1 - m)) (1 - m)  with d the brightness of c_diff and s that of f0 (0 for
// s < 0.04), the quadratic 0.04 m^2 + (d + s - 0.08) m - (s - 0.04) = 0. The base colour then blends the colour each
// target asks for, base_d = c_diff / (1 - m) and base_s = (f0 - 0.04 (1 - m)) / m, by m^2 (clamped to [0,1]).
// Roughness is 1 - glossiness exactly; alpha is the diffuse alpha. The error it leaves against a direct spec-gloss
// evaluation is measured by tests/unit/test_spec_gloss.cpp (docs/materials.md quotes the figures).
#pragma once

#include <glm/glm.hpp>

namespace visbuf {

struct MetalRough {
  glm::dvec4 baseColor{1.0};  // linear RGBA, each in [0,1]
  double metallic = 0.0;      // [0,1]
  double roughness = 1.0;     // [0,1]
};

// diffuse: linear RGBA, specular: linear RGB, glossiness: each in [0,1] (values outside are clamped).
MetalRough specGlossToMetalRough(const glm::dvec4& diffuse, const glm::dvec3& specular, double glossiness);

}  // namespace visbuf
