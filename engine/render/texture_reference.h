// Double-precision CPU twin of material.glsl's texture sampling, for the per-pixel judge (pixel_judge.h): a baked
// texture (Scene::textures / textureClasses) sampled at a uv with its screen gradients, as the Vulkan spec's
// isotropic filtering defines it and the shader does it by hand: KHR_texture_transform on uv and gradients,
// lambda = log2(max(|duv/dx|, |duv/dy|) x size), magnification below lambda 0, then the sampler's mip mode (none:
// level 0, nearest: level ceil(lambda + 1/2) - 1, linear: between floor(lambda) and the next), nearest or bilinear
// texels with the wrap modes. Texels are decoded as the GPU's formats do: sRGB classes to linear per texel before
// filtering (the _SRGB image formats), BC blocks through decodeTextureImageExact (the spec's palette, unrounded:
// BC5 normal maps carry more than 8 bits, and a highlight on a smooth surface resolves them).
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/scene/scene.h"

namespace visbuf {

class TextureReference {
 public:
  explicit TextureReference(const Scene& scene) : scene_(scene) {}

  // Linear RGBA of `ref` (baked: ref.baked names one of the scene's textures) at `uv` with screen gradients
  // `duvdx`, `duvdy` (per pixel step), before the texture transform. White for an unbaked reference (the GPU's
  // TEXTURE_NONE).
  glm::dvec4 sample(const TextureRef& ref, glm::dvec2 uv, glm::dvec2 duvdx, glm::dvec2 duvdy);

 private:
  glm::dvec4 texel(const TextureClass& c, uint32_t cls, uint32_t layer, uint32_t mip, int x, int y);
  glm::dvec4 sampleLevel(const TextureClass& c, uint32_t cls, uint32_t layer, glm::dvec2 uv, uint32_t mip,
                         bool linear, WrapMode wrapS, WrapMode wrapT);

  const Scene& scene_;
  // Block-compressed levels decoded on first use (RGBA in [0, 1]), by (class, layer, mip).
  std::unordered_map<uint64_t, std::vector<double>> decoded_;
};

}  // namespace visbuf
