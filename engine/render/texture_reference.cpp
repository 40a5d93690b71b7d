#include "visbuf/render/texture_reference.h"

#include <algorithm>
#include <cmath>

namespace visbuf {

namespace {

int wrapTexel(int i, int n, WrapMode mode) {
  if (mode == WrapMode::ClampToEdge) return std::clamp(i, 0, n - 1);
  if (mode == WrapMode::MirroredRepeat) {
    const int t = i - 2 * n * int(std::floor(double(i) / double(2 * n)));
    return t < n ? t : 2 * n - 1 - t;
  }
  return i - n * int(std::floor(double(i) / double(n)));  // Repeat
}

// The sRGB transfer function's inverse (IEC 61966-2-1), as an _SRGB format's texel fetch applies it.
double srgbToLinear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

}  // namespace

glm::dvec4 TextureReference::texel(const TextureClass& c, uint32_t cls, uint32_t layer, uint32_t mip, int x, int y) {
  const uint32_t side = c.mipSize(mip);
  glm::dvec4 t;
  if (c.format == TextureFormat::Rgba8) {
    const uint8_t* rgba = c.texels.data() + c.offset(mip, layer) + (uint64_t(y) * side + uint64_t(x)) * 4;
    t = glm::dvec4(rgba[0], rgba[1], rgba[2], rgba[3]) / 255.0;
  } else {
    const uint64_t key = uint64_t(cls) << 40 | uint64_t(layer) << 8 | mip;
    auto it = decoded_.find(key);
    if (it == decoded_.end())
      it = decoded_.emplace(key, decodeTextureImageExact(c.texels.data() + c.offset(mip, layer), side, side, c.format))
               .first;
    const double* rgba = it->second.data() + (uint64_t(y) * side + uint64_t(x)) * 4;
    t = glm::dvec4(rgba[0], rgba[1], rgba[2], rgba[3]);
  }
  if (c.colorSpace == ColorSpace::Srgb)
    for (int k = 0; k < 3; ++k) t[k] = srgbToLinear(t[k]);
  return t;
}

glm::dvec4 TextureReference::sampleLevel(const TextureClass& c, uint32_t cls, uint32_t layer, glm::dvec2 uv,
                                         uint32_t mip, bool linear, WrapMode wrapS, WrapMode wrapT) {
  const int size = int(c.mipSize(mip));
  if (!linear) {
    const int x = int(std::floor(uv.x * size)), y = int(std::floor(uv.y * size));
    return texel(c, cls, layer, mip, wrapTexel(x, size, wrapS), wrapTexel(y, size, wrapT));
  }
  const glm::dvec2 f = uv * double(size) - 0.5;
  const int x0 = int(std::floor(f.x)), y0 = int(std::floor(f.y));
  const glm::dvec2 a = f - glm::dvec2(x0, y0);
  const int xa = wrapTexel(x0, size, wrapS), xb = wrapTexel(x0 + 1, size, wrapS);
  const int ya = wrapTexel(y0, size, wrapT), yb = wrapTexel(y0 + 1, size, wrapT);
  const glm::dvec4 top = glm::mix(texel(c, cls, layer, mip, xa, ya), texel(c, cls, layer, mip, xb, ya), a.x);
  const glm::dvec4 bottom = glm::mix(texel(c, cls, layer, mip, xa, yb), texel(c, cls, layer, mip, xb, yb), a.x);
  return glm::mix(top, bottom, a.y);
}

glm::dvec4 TextureReference::sample(const TextureRef& ref, glm::dvec2 uv, glm::dvec2 duvdx, glm::dvec2 duvdy) {
  if (ref.baked < 0 || size_t(ref.baked) >= scene_.textures.size()) return glm::dvec4(1.0);
  const Texture& tex = scene_.textures[size_t(ref.baked)];
  const TextureClass& c = scene_.textureClasses[tex.sizeClass];
  const glm::dmat2 m(glm::dvec2(ref.transform[0]), glm::dvec2(ref.transform[1]));
  uv = m * uv + glm::dvec2(ref.transform[2]);
  duvdx = m * duvdx;
  duvdy = m * duvdy;
  const SamplerState& s = ref.sampler;
  const double rho = std::max(glm::length(duvdx), glm::length(duvdy)) * double(c.size);
  double lambda = rho > 0.0 ? std::log2(rho) : -128.0;
  if (lambda <= 0.0)
    return sampleLevel(c, tex.sizeClass, tex.layer, uv, 0, s.magFilter == TextureFilter::Linear, s.wrapS, s.wrapT);
  const bool linear = s.minFilter == TextureFilter::Linear;
  const double maxLevel = double(c.mipCount - 1);
  lambda = std::min(lambda, maxLevel);
  if (s.mipFilter == MipFilter::None) return sampleLevel(c, tex.sizeClass, tex.layer, uv, 0, linear, s.wrapS, s.wrapT);
  if (s.mipFilter == MipFilter::Nearest) {
    const uint32_t level = uint32_t(std::min(std::ceil(lambda + 0.5) - 1.0, maxLevel));
    return sampleLevel(c, tex.sizeClass, tex.layer, uv, level, linear, s.wrapS, s.wrapT);
  }
  const uint32_t l0 = uint32_t(std::floor(lambda));
  const double f = lambda - double(l0);
  const glm::dvec4 a = sampleLevel(c, tex.sizeClass, tex.layer, uv, l0, linear, s.wrapS, s.wrapT);
  if (f == 0.0 || l0 + 1 >= c.mipCount) return a;
  return glm::mix(a, sampleLevel(c, tex.sizeClass, tex.layer, uv, l0 + 1, linear, s.wrapS, s.wrapT), f);
}

}  // namespace visbuf
