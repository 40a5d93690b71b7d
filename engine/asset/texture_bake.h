// Texture baking for `visbuf bake`: the images that materials reference are decoded (OpenImageIO: PNG, JPEG;
// embedded or external), resized to a square power of two, given a full box-filtered mip chain and grouped
// into size classes (engine/scene/texture.h; docs/pack-format.md explains the layout).
//
// Per image, in this order:
//   1. Decode to float RGBA (grey -> RGB, no alpha -> 1; alpha stays straight, not premultiplied). Colour
//      textures (base colour, emissive) are sRGB: their RGB is converted to linear light here. An 8-bit file
//      is converted through a table of its 256 codes (codeToLinear), and when it is a square power of two its
//      codes are kept as mip 0 (they are what step 4 would give back) and level 1 is averaged from them.
//   2. Size: S = min(maxTextureSize, P) where P is the power of two NEAREST to the larger side (ties round up:
//      300 -> 256, 400 -> 512, 384 -> 512), so that side is stretched by at most 4/3 or shrunk to no less than
//      2/3. Non-square images become S x S, stretching the shorter side (the shader's uvs span [0,1] either
//      way; REPEAT / MIRRORED_REPEAT then wrap in hardware exactly as glTF asks, which a sub-rectangle of a
//      bigger layer could not).
//      A square power-of-two image needs no resampling: its own mip chain is built and the levels above S
//      dropped. Anything else is resampled once with OpenImageIO's resize (filtered, in linear light), after
//      2:1 box reductions per axis while the half stays >= S (so the filter spans under 2 texels: linear time).
//      Memory per image: texture_decode.h (imageBakePeakBytes); images baked at once share a 1.5 GiB budget.
//   3. Mip chain to 1x1: each level is the 2x2 box average of the previous one, in linear light (float).
//   4. Encode RGBA8: sRGB textures re-encode RGB with the sRGB curve (exactly rounded), alpha linear; data
//      textures (normal, metallic-roughness, occlusion) are linear throughout.
//   5. Block compression (TextureEncoding::Bc, the default; libsquish), of every mip level's RGBA8 bytes, so sRGB
//      colour is compressed as encoded (the GPU's *_SRGB_BLOCK formats decode after the block decode). The format
//      follows the slots that use the image (chooseTextureFormat): base colour / emissive BC1, or BC3 when a base
//      colour's alpha is not all 255; normal-only BC5 (x, y; the shader rebuilds z: the normal and clearcoat
//      normal slots); R-only BC4 (occlusion, clearcoat); metallic-roughness and any other linear mix BC1. Levels below 4x4 are one whole block, the missing texels
//      left out of the fit. Blocks are independent, so each level is compressed in parallel bands of block rows
//      whose output ranges are fixed in advance: the bytes do not depend on the thread count.
//
// Images are baked in parallel (oneTBB); classes are assembled afterwards in the same order as a serial bake.
//
// An image used both as colour and as data (rare) is baked twice, once per colour space.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// Default pixel budget of one image (TextureBakeOptions::maxImagePixels, `--max-image-pixels`): 64 Mpixel
// (8192 x 8192), checked from the image header before any pixel is decoded.
inline constexpr uint64_t kDefaultMaxImagePixels = uint64_t{64} << 20;
// Largest encoded image file read (external images): 1 GiB.
inline constexpr uint64_t kMaxImageFileBytes = uint64_t{1} << 30;
// The largest baked texture side (TextureBakeOptions::maxTextureSize) and the layers of one texture class (Vulkan's
// guaranteed minimum of maxImageArrayLayers: a 257th image of a class opens another).
inline constexpr uint32_t kMaxBakedTextureSize = 16384;
inline constexpr uint32_t kMaxTextureClassLayers = 256;

// How baked textures are stored (`visbuf bake --textures bc|rgba8`).
enum class TextureEncoding { Bc, Rgba8 };
// libsquish's colour fit for BC1 / BC3 (`--texture-quality`): Fast = range fit, Normal = cluster fit, High =
// iterative cluster fit. BC4 / BC5 (and BC3's alpha) are fitted the same way at every quality.
enum class TextureQuality { Fast, Normal, High };
const char* textureQualityName(TextureQuality quality);  // "fast", "normal", "high"

struct TextureBakeOptions {
  uint32_t maxTextureSize = 2048;  // power of two in [1, 16384]; larger images are downscaled to it
  // Images whose header declares more than this many pixels (width x height) are refused before decoding
  // (CapacityExceeded): a 1 MiB PNG can declare 16384 x 16384 and would take 4 GiB once decoded.
  uint64_t maxImagePixels = kDefaultMaxImagePixels;
  TextureEncoding encoding = TextureEncoding::Bc;
  // Range fit by default: DamagedHelmet rendered from its BC pack is 45 dB PSNR from the RGBA8 pack's image
  // (cluster fit: 48 dB for a texture bake ~5x longer; docs/pack-format.md).
  TextureQuality quality = TextureQuality::Fast;
  // An image that cannot be decoded (MalformedInput: corrupt, truncated, a format visbuf does not decode such as
  // KTX2 or WebP; FileNotFound: its file is missing) drops its texture from every material slot that uses it,
  // with a warning in TextureBakeReport::warnings, as glTF viewers do. false (CLI --strict-images): the bake
  // fails on it. Budget refusals (CapacityExceeded), files that are not regular and builds without a decoder
  // (Unsupported) always fail: they say something the user must decide.
  bool dropUndecodableImages = true;
  // Largest side of an image used only as a normal map (power of two; 0: maxTextureSize applies): its larger
  // levels are dropped after the mip chain is built (`bake --normal-map-size`; docs/pack-format.md measures it).
  uint32_t maxNormalMapSize = 0;
};

// A decoded image in linear light: width x height RGBA floats, row-major from the top row.
struct LinearImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<float> rgba;
};

// One baked image: square, power-of-two `size`, mips[m] is the level max(size >> m, 1) wide in `format`
// (textureImageBytes bytes).
struct BakedImage {
  uint32_t size = 0;
  TextureFormat format = TextureFormat::Rgba8;
  uint32_t originalWidth = 0, originalHeight = 0;
  std::vector<std::vector<uint8_t>> mips;
  std::string resizeNote;  // e.g. "211x211 -> 256x256 (non-power-of-two: nearest power of two)"; empty: none
};

// Called after each texture is baked: (done, total, name of the texture).
using TextureBakeProgress = std::function<void(size_t done, size_t total, const std::string& name)>;

struct TextureBakeReport {
  std::vector<std::string> notes;     // one line per resized image
  std::vector<std::string> warnings;  // one line per image dropped (TextureBakeOptions::dropUndecodableImages)
  uint64_t texelBytes = 0;         // all classes, all mips
  uint64_t rgba8Bytes = 0;         // what the same classes take as RGBA8 (texelBytes without compression)
};

// Bakes every image referenced by scene->materials (TextureRef::image indexes imported.images) into
// scene->textures / scene->textureClasses, and sets each reference's `baked`. Textures are numbered in order of
// first use (materials in order; slots base colour, metallic-roughness, normal, occlusion, emissive); classes
// in order of first use, at most 256 layers each (Vulkan's guaranteed maxImageArrayLayers: a 257th image of
// the same size and colour space opens a second class).
// External image files are read only when they are regular files (opened without blocking and with
// O_NOFOLLOW, at most kMaxImageFileBytes: core/file_read.h); their paths were checked and made link-free by
// the importer's URI rule (ImportedImage::path).
// Errors (each names the glTF image): InvalidArgument (bad maxTextureSize / maxImagePixels, an external image
// that is not a regular file), FileNotFound / IoError (an external image file that is missing or unreadable),
// MalformedInput (bytes that are not a decodable PNG/JPEG, a truncated or corrupt image, an image index out of
// range, an empty embedded image), CapacityExceeded (a side over 16384, more pixels than maxImagePixels, a file over
// kMaxImageFileBytes), Unsupported (a build without OpenImageIO).
Status bakeTextures(const ImportedScene& imported, const TextureBakeOptions& options, Scene* scene,
                    TextureBakeReport* report = nullptr, const TextureBakeProgress& progress = {});

// --- the steps, for tests and tools

// sRGB transfer functions (IEC 61966-2-1), on [0,1] (clamped).
float srgbToLinear(float v);
float linearToSrgb(float v);
// Linear [0,1] value -> round(255 * linearToSrgb(v)) computed exactly (a table of the 255 decision points).
uint8_t encodeSrgb8(float linear);

// The baked size of a width x height image (step 2 above). Both must be >= 1; maxSize a power of two.
uint32_t bakedTextureSize(uint32_t width, uint32_t height, uint32_t maxSize);
// Mip levels of a square power-of-two image down to 1x1, level 0 first (step 3).
std::vector<LinearImage> buildMipChain(LinearImage level0);
// RGBA8 encoding (step 4).
std::vector<uint8_t> encodeRgba8(const LinearImage& image, ColorSpace colorSpace);

// Bit i set: the image is used by texture slot i (textureSlots() order: base colour, metallic-roughness, normal,
// occlusion, emissive, clearcoat, clearcoat roughness, clearcoat normal).
using TextureSlotMask = uint32_t;
inline constexpr TextureSlotMask kNormalSlotMask = 1u << 2;  // an image used by normal slots only (BC5 or RGBA8)
// The stored format of an image (step 5): `opaque` says every alpha of its RGBA8 mip 0 is 255.
TextureFormat chooseTextureFormat(TextureEncoding encoding, TextureSlotMask slots, ColorSpace colorSpace, bool opaque);
// Block-compresses one width x height RGBA8 image (rows top first, R first) into `format` (a BC format):
// textureImageBytes(format, width, height) bytes, blocks row-major. BC1 / BC3 take RGB(A), BC4 R, BC5 R and G.
// Blocks are compressed in parallel; the result is the same whatever the thread count.
std::vector<uint8_t> compressBlocks(const uint8_t* rgba, uint32_t width, uint32_t height, TextureFormat format,
                                    TextureQuality quality);
// (The inverse, decodeTextureImage, is in scene/texture.h: the GPU upload uses it where BC is unavailable.)
// The class an image goes to, as far as its format is concerned.
struct TextureClassKey {
  uint32_t size = 0;
  ColorSpace colorSpace = ColorSpace::Linear;
  TextureFormat format = TextureFormat::Rgba8;
};
// Classes the images make (one per (size, colour space, format), one more per 256 layers).
size_t countTextureClasses(const std::vector<TextureClassKey>& images);
// Separate formats multiply the classes (up to 5 per size, against 2 with RGBA8), and the shading pass binds at
// most MAX_TEXTURE_CLASSES: while the images make more classes than `maxClasses`, formats are folded into one
// that holds them, in this order: BC4 -> BC1, BC5 -> BC1 (linear), sRGB BC1 -> BC3. Returns the classes after.
size_t fitTextureClassFormats(std::vector<TextureClassKey>& images, size_t maxClasses);
// Step 5 for a baked image: every RGBA8 level becomes `format` (Rgba8: unchanged).
void compressBakedImage(BakedImage* image, TextureFormat format, TextureQuality quality);

// Decodes an encoded PNG/JPEG (`name` starts error messages); RGB converted to linear when colorSpace is Srgb.
// The header's width x height is checked against `maxPixels` (and each side against 16384) before any pixel
// is decoded (CapacityExceeded). Any error the decoder reports, a truncated file included ("Premature end of
// JPEG file"), is MalformedInput: no partially decoded image is ever returned.
Result<LinearImage> decodeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace,
                                uint64_t maxPixels = kDefaultMaxImagePixels);
// decodeImage as the bake uses it: an 8-bit file keeps its codes (`codes`: RGBA8, grey expanded to RGB, missing
// alpha 255; `linear` empty), so that a square power-of-two image's mip 0 is its own bytes and level 1 is averaged
// straight from them; a deeper file is decoded to `linear` (`codes` empty). Same checks and errors as decodeImage.
struct DecodedImage {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> codes;
  LinearImage linear;
};
Result<DecodedImage> decodeImageForBake(const uint8_t* bytes, size_t size, const std::string& name,
                                        ColorSpace colorSpace, uint64_t maxPixels = kDefaultMaxImagePixels);
// The linear value of 8-bit code `code` as decodeImage gives it: code / 255, through srgbToLinear for the RGB of
// an sRGB image. Every code survives encodeRgba8 of its value unchanged (the bake relies on it for mip 0).
float codeToLinear(uint8_t code, bool srgb);

// Resamples (OpenImageIO resize, linear light) to width x height.
Result<LinearImage> resizeImage(const LinearImage& image, uint32_t width, uint32_t height);
// Steps 1-4 for one encoded image (RGBA8 levels; compressBakedImage is step 5).
Result<BakedImage> bakeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace,
                             uint32_t maxTextureSize, uint64_t maxPixels = kDefaultMaxImagePixels);
// Steps 2-4 for a decoded image.
Result<BakedImage> bakeDecodedImage(DecodedImage decoded, const std::string& name, ColorSpace colorSpace,
                                    uint32_t maxTextureSize);

// KHR_materials_pbrSpecularGlossiness textures (Material::specGloss), converted before the bake: each such
// material's diffuse and specular-glossiness images are decoded (RGB through the sRGB curve, alpha linear) and
// converted texel by texel with specGlossToMetalRough (scene/spec_gloss.h, the extension's factors applied) into a
// base colour image (sRGB RGBA8) over the diffuse texture's texels and a metallic-roughness image (linear; G
// roughness, B metallic) over the specular-glossiness texture's texels, the other texture sampled bilinearly at the
// same uv (a material with one of the two textures: both images over its texels, the other input its factor). When
// the two textures use different TEXCOORD sets or transforms each image converts against the other's factor (a
// note says so). The images are appended to `derived` (ImportedImage::rgba8; image indices continue after
// imported.images), the two slots point at them (each keeping its source texture's sampler, set and transform),
// the material's baseColor / metallic / roughness become 1 and specGloss is cleared. Errors: those of decodeImage
// and of reading an external image file.
Status convertSpecGlossTextures(const ImportedScene& imported, const TextureBakeOptions& options, Scene* scene,
                                std::vector<ImportedImage>* derived, std::vector<std::string>* notes);

}  // namespace visbuf
