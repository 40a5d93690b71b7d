// Textures of a scene: how materials refer to them (TextureRef) and how baked pixels are stored
// (Texture + TextureClass). docs/pack-format.md ("Textures") gives the reasons for the layout.
//
// Baked layout (the shading pass runs on lavapipe without descriptor indexing):
//   - Every baked image is square, power-of-two sized, with a full box-filtered mip chain to 1x1, stored as RGBA8
//     or block-compressed (BC1 / BC3 / BC4 / BC5: TextureFormat).
//   - Images of the same (size, colour space, format) share one 2D ARRAY texture, a TextureClass; each image is one
//     layer of it. A shader addresses a texture as (class, layer): it binds one sampler2DArray per class
//     (a handful: sizes x colour spaces x formats, at most MAX_TEXTURE_CLASSES) and, since the shade pass runs
//     per material, indexes that array with a dynamically uniform class index, which core Vulkan allows
//     without descriptor indexing; the layer is the third texture coordinate.
//   - Sampler state (wrap, filter) is not part of the image: it travels with each TextureRef, so one image
//     can be sampled with several samplers (glTF allows it) and the renderer needs only a few VkSamplers.
#pragma once

#include <algorithm>
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

// Storage format of a texture class. Values are stored in packs: never renumber.
//   Rgba8: 4 bytes a texel, R first.
//   Bc1..Bc5: 4x4 blocks (BC1 = DXT1 RGB, 8 bytes; BC3 = DXT5 RGBA, 16; BC4 = one channel (R), 8; BC5 = two
//   channels (R, G), 16), blocks row-major within a level, bytes as Vulkan's VK_FORMAT_BC*_BLOCK read them.
enum class TextureFormat : uint32_t { Rgba8 = 0, Bc1 = 1, Bc3 = 2, Bc4 = 3, Bc5 = 4 };
inline constexpr uint32_t kTextureFormatCount = 5;
const char* textureFormatName(TextureFormat format);  // "rgba8", "bc1", ...
bool isBlockCompressed(TextureFormat format);
// Bytes of one texel (Rgba8) or one 4x4 block (BC formats).
uint32_t textureFormatUnitBytes(TextureFormat format);
// Bytes of one width x height image in `format`. BC images are whole 4x4 blocks: a 2x2 or 1x1 level still takes
// one block (Vulkan's rule: buffer-image copies of block formats cover whole blocks; the image extent stays the
// level's true size).
uint64_t textureImageBytes(TextureFormat format, uint32_t width, uint32_t height);

// Decodes one width x height image stored in `format` (textureImageBytes bytes) to RGBA8 as Vulkan's decode of
// the matching format gives it, rounded to 8 bits: BC1 (RGB block format: alpha 255, and 3-colour blocks' fourth
// colour black), BC3, BC4 (R, 0, 0, 255), BC5 (R, G, 0, 255); Rgba8 is copied. Interpolated colours are computed
// in integers from the 8-bit endpoints, so a GPU's float decode may differ by 1.
std::vector<uint8_t> decodeTextureImage(const uint8_t* data, uint32_t width, uint32_t height, TextureFormat format);
// The same decode without rounding, RGBA in [0, 1]: BC endpoints expanded and interpolated exactly as the Vulkan
// spec defines the formats (what a GPU's float decode approximates); Rgba8 texels / 255. The per-pixel judge's
// texels (engine/render/texture_reference.h).
std::vector<double> decodeTextureImageExact(const uint8_t* data, uint32_t width, uint32_t height, TextureFormat format);

// One 2D array texture: `layers` square images of `size` x `size` texels in `format` with `mipCount` levels.
// texels holds mip 0 of every layer, then mip 1 of every layer, ... (mip-major: one buffer-to-image copy
// region per mip level covers all layers). Level m is max(size >> m, 1) texels wide. Rgba8: 4 bytes a texel,
// R first; BC formats: ceil(side / 4)^2 blocks a layer (textureImageBytes). Srgb classes store sRGB-encoded RGB
// (alpha is always linear); Bc4 / Bc5 classes are always Linear.
struct TextureClass {
  uint32_t size = 0;      // power of two, >= 1
  ColorSpace colorSpace = ColorSpace::Linear;
  uint32_t layers = 0;    // >= 1
  uint32_t mipCount = 0;  // log2(size) + 1
  TextureFormat format = TextureFormat::Rgba8;
  std::vector<uint8_t> texels;
  bool operator==(const TextureClass&) const = default;

  static uint32_t mipCountFor(uint32_t size);
  uint32_t mipSize(uint32_t mip) const { return std::max(size >> mip, 1u); }
  // Bytes of one layer at mip level `mip`, and the byte offset of (mip, layer) in texels.
  uint64_t layerBytes(uint32_t mip) const;
  uint64_t offset(uint32_t mip, uint32_t layer) const;
  uint64_t totalBytes() const;  // what texels.size() must be
};

}  // namespace visbuf
