// Textures of a scene: how materials refer to them (TextureRef) and how baked pixels are stored
// (Texture + TextureClass). docs/pack-format.md ("Textures") gives the reasons for the layout.
//
// Baked layout (the shading pass runs on lavapipe without descriptor indexing):
//   - Every baked image is square, power-of-two sized, RGBA8, with a full box-filtered mip chain to 1x1.
//   - Images of the same (size, colour space) share one 2D ARRAY texture, a TextureClass; each image is one
//     layer of it. A shader addresses a texture as (class, layer): it binds one sampler2DArray per class
//     (a handful: at most 12 sizes x 2 colour spaces) and, since the shade pass runs per material, indexes
//     that array with a dynamically uniform class index, which core Vulkan allows without descriptor
//     indexing; the layer is the third texture coordinate.
//   - Sampler state (wrap, filter) is not part of the image: it travels with each TextureRef, so one image
//     can be sampled with several samplers (glTF allows it) and the renderer needs only a few VkSamplers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace visbuf {

// Values are stored in packs: never renumber.
enum class WrapMode : uint32_t { Repeat = 0, ClampToEdge = 1, MirroredRepeat = 2 };
enum class TextureFilter : uint32_t { Nearest = 0, Linear = 1 };
enum class MipFilter : uint32_t { None = 0, Nearest = 1, Linear = 2 };  // None: sample mip 0 only
enum class ColorSpace : uint32_t { Linear = 0, Srgb = 1 };

// A glTF sampler. glTF's undefined filters become Linear / MipFilter::Linear (trilinear).
struct SamplerState {
  WrapMode wrapS = WrapMode::Repeat;
  WrapMode wrapT = WrapMode::Repeat;
  TextureFilter magFilter = TextureFilter::Linear;
  TextureFilter minFilter = TextureFilter::Linear;
  MipFilter mipFilter = MipFilter::Linear;
  bool operator==(const SamplerState&) const = default;
};

// A material's reference to a texture. Import fills the glTF side (texture, image, uri, texCoord, sampler,
// transform); texture baking sets `baked`.
struct TextureRef {
  int32_t texture = -1;  // source glTF texture index; -1: no texture
  int32_t image = -1;    // source glTF image index; -1: none or unknown
  uint32_t texCoord = 0; // TEXCOORD_n set the texture is sampled with (after KHR_texture_transform's override)
  std::string uri;       // image URI as written in the glTF (relative to it); empty for embedded images
  // KHR_texture_transform as a 3x2 matrix (3 columns of vec2): uv' = transform * vec3(uv, 1), i.e.
  // T(offset) * R(rotation) * S(scale) of the extension; identity without it.
  glm::mat3x2 transform{1.0f};
  SamplerState sampler;
  int32_t baked = -1;    // index into Scene::textures once baked; -1: not baked (no texture, or not baked)
  bool operator==(const TextureRef&) const = default;
};

// One baked image: a layer of a TextureClass.
struct Texture {
  std::string name;         // the image's name, else its URI, else "image N" (for messages and stats)
  int32_t sourceImage = -1; // source glTF image index
  ColorSpace colorSpace = ColorSpace::Linear;
  uint32_t sizeClass = 0;   // into Scene::textureClasses
  uint32_t layer = 0;       // < that class's layers
  uint32_t originalWidth = 0, originalHeight = 0;  // of the source image, before resizing
  bool operator==(const Texture&) const = default;
};

// One 2D array texture: `layers` square images of `size` x `size` RGBA8 texels with `mipCount` levels.
// texels holds mip 0 of every layer, then mip 1 of every layer, ... (mip-major: one buffer-to-image copy
// region per mip level covers all layers). Level m is max(size >> m, 1) texels wide; each texel is 4 bytes,
// R first. Srgb classes store sRGB-encoded RGB (alpha is always linear).
struct TextureClass {
  uint32_t size = 0;      // power of two, >= 1
  ColorSpace colorSpace = ColorSpace::Linear;
  uint32_t layers = 0;    // >= 1
  uint32_t mipCount = 0;  // log2(size) + 1
  std::vector<uint8_t> texels;
  bool operator==(const TextureClass&) const = default;

  static uint32_t mipCountFor(uint32_t size);
  // Bytes of one layer at mip level `mip`, and the byte offset of (mip, layer) in texels.
  uint64_t layerBytes(uint32_t mip) const;
  uint64_t offset(uint32_t mip, uint32_t layer) const;
  uint64_t totalBytes() const;  // what texels.size() must be
};

}  // namespace visbuf
