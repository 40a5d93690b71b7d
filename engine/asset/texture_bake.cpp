// Texture baking: size rule, mip chains, sRGB encoding, size classes (contract in texture_bake.h). Decoding and
// resampling live in texture_decode_oiio.cpp (texture_decode_none.cpp without OpenImageIO).
#include "visbuf/asset/texture_bake.h"

#include <fmt/format.h>
#include <squish.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <tuple>
#include <utility>

#include "visbuf/asset/texture_decode.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"
#include "visbuf/shared/config.h"

namespace visbuf {

namespace {

constexpr uint32_t kMaxTextureSize = kMaxBakedTextureSize;
constexpr uint32_t kMaxLayersPerClass = kMaxTextureClassLayers;

// The linear value whose sRGB encoding lies halfway between codes k and k + 1 (k = 0..254): encodeSrgb8(v) =
// number of midpoints below v = round(255 * encode(v)), rounded in the encoded domain as GPUs and image tools do.
std::array<float, 255> makeSrgbMidpoints() {
  std::array<float, 255> mid{};
  auto decode = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  for (int k = 0; k < 255; ++k) mid[size_t(k)] = float(decode((k + 0.5) / 255.0));
  return mid;
}

int squishFlags(TextureFormat format, TextureQuality quality) {
  const int fit = quality == TextureQuality::Fast     ? squish::kColourRangeFit
                  : quality == TextureQuality::Normal ? squish::kColourClusterFit
                                                      : squish::kColourIterativeClusterFit;
  switch (format) {
    case TextureFormat::Bc1: return squish::kDxt1 | fit;
    case TextureFormat::Bc3: return squish::kDxt5 | fit;
    case TextureFormat::Bc4: return squish::kBc4;
    case TextureFormat::Bc5: return squish::kBc5;
    case TextureFormat::Rgba8: break;
  }
  return 0;
}

// Block rows per parallel task: a 2048-wide level has 512 blocks a row, so a task is ~4k blocks; levels of 32
// rows or fewer are one task.
constexpr size_t kBlockRowsPerTask = 8;

}  // namespace

const char* textureQualityName(TextureQuality quality) {
  switch (quality) {
    case TextureQuality::Fast: return "fast";
    case TextureQuality::Normal: return "normal";
    case TextureQuality::High: return "high";
  }
  return "unknown";
}

TextureFormat chooseTextureFormat(TextureEncoding encoding, TextureSlotMask slots, ColorSpace colorSpace, bool opaque) {
  if (encoding == TextureEncoding::Rgba8) return TextureFormat::Rgba8;
  constexpr TextureSlotMask kBaseColor = 1u << TEXTURE_SLOT_BASE_COLOR;
  constexpr TextureSlotMask kNormals = 1u << TEXTURE_SLOT_NORMAL | 1u << TEXTURE_SLOT_CLEARCOAT_NORMAL;
  constexpr TextureSlotMask kRedOnly = 1u << TEXTURE_SLOT_OCCLUSION | 1u << TEXTURE_SLOT_CLEARCOAT;
  if (colorSpace == ColorSpace::Srgb) return (slots & kBaseColor) && !opaque ? TextureFormat::Bc3 : TextureFormat::Bc1;
  // The normal slots read xy (z is rebuilt), occlusion and clearcoat R alone; metallic-roughness (G, B), clearcoat
  // roughness (G) and images shared across those groups keep three channels.
  if ((slots & ~kNormals) == 0) return TextureFormat::Bc5;
  if ((slots & ~kRedOnly) == 0) return TextureFormat::Bc4;
  return TextureFormat::Bc1;
}

std::vector<uint8_t> compressBlocks(const uint8_t* rgba, uint32_t width, uint32_t height, TextureFormat format,
                                    TextureQuality quality) {
  const uint32_t unit = textureFormatUnitBytes(format);
  const uint32_t bx = (width + 3) / 4, by = (height + 3) / 4;
  std::vector<uint8_t> out(textureImageBytes(format, width, height));
  if (!isBlockCompressed(format) || width == 0 || height == 0) return out;
  const int flags = squishFlags(format, quality);
  const bool opaqueBc1 = format == TextureFormat::Bc1;
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, by, kBlockRowsPerTask), [&](const tbb::blocked_range<uint32_t>& r) {
    uint8_t block[16 * 4];
    for (uint32_t row = r.begin(); row != r.end(); ++row) {
      for (uint32_t col = 0; col < bx; ++col) {
        int mask = 0;  // texels inside the image; the others (levels below 4x4) are left out of the fit
        for (uint32_t y = 0; y < 4; ++y) {
          for (uint32_t x = 0; x < 4; ++x) {
            const uint32_t px = col * 4 + x, py = row * 4 + y;
            uint8_t* dst = &block[(y * 4 + x) * 4];
            if (px < width && py < height) {
              std::memcpy(dst, &rgba[(size_t(py) * width + px) * 4], 4);
              // BC1 here is the RGB format: libsquish would turn texels with alpha below 128 into 3-colour
              // mode's transparent black, which the RGB format reads as black.
              if (opaqueBc1) dst[3] = 255;
              mask |= 1 << (y * 4 + x);
            } else {
              std::memset(dst, 0, 4);
            }
          }
        }
        squish::CompressMasked(block, mask, &out[(size_t(row) * bx + col) * unit], flags);
      }
    }
  });
  return out;
}

size_t countTextureClasses(const std::vector<TextureClassKey>& images) {
  std::map<std::tuple<uint32_t, ColorSpace, TextureFormat>, size_t> layers;
  for (const TextureClassKey& k : images) ++layers[{k.size, k.colorSpace, k.format}];
  size_t classes = 0;
  for (const auto& [key, n] : layers) classes += (n + kMaxLayersPerClass - 1) / kMaxLayersPerClass;
  return classes;
}

size_t fitTextureClassFormats(std::vector<TextureClassKey>& images, size_t maxClasses) {
  // Each step folds formats into one that can stand in for them: BC1 (linear) holds BC4's R and BC5's x, y
  // (with z: the shader then reads the normal's three channels), BC3 holds opaque sRGB BC1 colour (alpha 255).
  auto fold = [&](auto&& from, TextureFormat to) {
    for (TextureClassKey& k : images)
      if (from(k)) k.format = to;
  };
  if (countTextureClasses(images) > maxClasses)
    fold([](const TextureClassKey& k) { return k.format == TextureFormat::Bc4; }, TextureFormat::Bc1);
  if (countTextureClasses(images) > maxClasses)
    fold([](const TextureClassKey& k) { return k.format == TextureFormat::Bc5; }, TextureFormat::Bc1);
  if (countTextureClasses(images) > maxClasses) {
    fold([](const TextureClassKey& k) { return k.format == TextureFormat::Bc1 && k.colorSpace == ColorSpace::Srgb; },
         TextureFormat::Bc3);
  }
  return countTextureClasses(images);
}

void compressBakedImage(BakedImage* image, TextureFormat format, TextureQuality quality) {
  if (image->format == format || !isBlockCompressed(format)) return;
  for (size_t m = 0; m < image->mips.size(); ++m) {
    const uint32_t side = std::max(image->size >> m, 1u);
    image->mips[m] = compressBlocks(image->mips[m].data(), side, side, format, quality);
  }
  image->format = format;
}

float srgbToLinear(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

uint8_t encodeSrgb8(float linear) {
  // The code is the number of midpoints below `linear`. A table over 8192 equal steps of [0, 1] gives that count
  // at each step's lower edge; the walk up from there is exact and short (at most 2 codes a step near 0, where
  // the curve is steepest).
  constexpr int kSteps = 8192;
  static const std::array<float, 255> kMidpoints = makeSrgbMidpoints();
  static const std::array<uint8_t, kSteps> kStart = [] {
    std::array<uint8_t, kSteps> start{};
    for (int i = 0; i < kSteps; ++i) {
      const float edge = float(i) / float(kSteps);
      start[size_t(i)] = uint8_t(std::lower_bound(kMidpoints.begin(), kMidpoints.end(), edge) - kMidpoints.begin());
    }
    return start;
  }();
  if (!(linear > 0.0f)) return 0;  // also NaN
  if (linear >= 1.0f) return 255;
  // float(i) / kSteps <= linear for this i (exact: a power-of-two scale), so the count only grows from here.
  unsigned code = kStart[size_t(linear * float(kSteps))];
  while (code < 255 && kMidpoints[code] < linear) ++code;
  return uint8_t(code);
}

uint32_t bakedTextureSize(uint32_t width, uint32_t height, uint32_t maxSize) {
  const uint32_t side = std::max({width, height, 1u});
  const uint32_t lower = std::bit_floor(side);
  // Nearest power of two, ties up: side >= 1.5 * lower rounds up (64-bit: lower can be 2^31).
  const uint64_t nearest = uint64_t{side} * 2 >= uint64_t{lower} * 3 ? uint64_t{lower} * 2 : lower;
  return uint32_t(std::min<uint64_t>(nearest, std::max(maxSize, 1u)));
}

namespace {
// The next mip level of a square power-of-two level wider than 1: each texel the 2x2 box average.
LinearImage halveLinear(const LinearImage& src) {
  LinearImage dst;
  dst.width = dst.height = src.width / 2;
  dst.rgba.resize(size_t(dst.width) * dst.height * 4);
  // Rows in parallel: every output texel is the same expression whichever thread computes it.
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, dst.height, 16), [&](const tbb::blocked_range<uint32_t>& rows) {
    for (uint32_t y = rows.begin(); y != rows.end(); ++y) {
      for (uint32_t x = 0; x < dst.width; ++x) {
        const float* a = &src.rgba[(size_t(2 * y) * src.width + 2 * x) * 4];
        const float* b = a + size_t(src.width) * 4;  // the row below
        float* out = &dst.rgba[(size_t(y) * dst.width + x) * 4];
        for (int c = 0; c < 4; ++c) out[c] = 0.25f * ((a[c] + a[4 + c]) + (b[c] + b[4 + c]));
      }
    }
  });
  return dst;
}
}  // namespace

std::vector<LinearImage> buildMipChain(LinearImage level0) {
  std::vector<LinearImage> chain;
  chain.push_back(std::move(level0));
  while (chain.back().width > 1) chain.push_back(halveLinear(chain.back()));
  return chain;
}

namespace {
// lround(clamp(v, 0, 1) * 255) without the libm call: x - floor(x) is exact for x in [0, 255].
uint8_t encodeUnorm8(float v) {
  const float x = std::clamp(v, 0.0f, 1.0f) * 255.0f;  // NaN -> clamp keeps NaN: treated as 0 below
  if (!(x > 0.0f)) return 0;
  const int whole = int(x);
  return uint8_t(whole + (x - float(whole) >= 0.5f ? 1 : 0));
}
}  // namespace

std::vector<uint8_t> encodeRgba8(const LinearImage& image, ColorSpace colorSpace) {
  std::vector<uint8_t> out(image.rgba.size());
  const size_t texels = image.rgba.size() / 4;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, texels, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin() * 4; i < r.end() * 4; ++i) {
      const float v = image.rgba[i];
      const bool srgb = colorSpace == ColorSpace::Srgb && i % 4 != 3;  // alpha is always linear
      out[i] = srgb ? encodeSrgb8(v) : encodeUnorm8(v);
    }
  });
  return out;
}

namespace {

// codeToLinear's values: [0] code / 255, [1] srgbToLinear(code / 255).
const std::array<std::array<float, 256>, 2>& codeTables() {
  static const std::array<std::array<float, 256>, 2> kTables = [] {
    std::array<std::array<float, 256>, 2> t{};
    for (int k = 0; k < 256; ++k) {
      t[0][size_t(k)] = float(k) / 255.0f;
      t[1][size_t(k)] = srgbToLinear(float(k) / 255.0f);
    }
    return t;
  }();
  return kTables;
}

}  // namespace

float codeToLinear(uint8_t code, bool srgb) { return codeTables()[srgb ? 1 : 0][code]; }

namespace {

// RGBA8 codes to linear floats (codeToLinear; alpha always linear). Rows in parallel.
LinearImage linearFromCodes(const std::vector<uint8_t>& codes, uint32_t width, uint32_t height, ColorSpace colorSpace) {
  LinearImage image;
  image.width = width;
  image.height = height;
  image.rgba.resize(codes.size());
  const float* colour = codeTables()[colorSpace == ColorSpace::Srgb ? 1 : 0].data();
  const float* alpha = codeTables()[0].data();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, codes.size() / 4, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin() * 4; i < r.end() * 4; ++i) image.rgba[i] = (i % 4 == 3 ? alpha : colour)[codes[i]];
  });
  return image;
}

// Level 1 of a square power-of-two image straight from its level-0 codes: the same 2x2 average buildMipChain
// computes from linearFromCodes(level 0), without materialising level 0 in float.
LinearImage halveCodes(const std::vector<uint8_t>& codes, uint32_t size, ColorSpace colorSpace) {
  LinearImage dst;
  dst.width = dst.height = size / 2;
  dst.rgba.resize(size_t(dst.width) * dst.height * 4);
  const float* colour = codeTables()[colorSpace == ColorSpace::Srgb ? 1 : 0].data();
  const float* alpha = codeTables()[0].data();
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, dst.height, 16), [&](const tbb::blocked_range<uint32_t>& rows) {
    for (uint32_t y = rows.begin(); y != rows.end(); ++y) {
      for (uint32_t x = 0; x < dst.width; ++x) {
        const uint8_t* a = &codes[(size_t(2 * y) * size + 2 * x) * 4];
        const uint8_t* b = a + size_t(size) * 4;  // the row below
        float* out = &dst.rgba[(size_t(y) * dst.width + x) * 4];
        for (int c = 0; c < 4; ++c) {
          const float* t = c == 3 ? alpha : colour;
          out[c] = 0.25f * ((t[a[c]] + t[a[4 + c]]) + (t[b[c]] + t[b[4 + c]]));
        }
      }
    }
  });
  return dst;
}

// 2:1 box reduction along x and / or y (an odd last column or row is averaged alone).
LinearImage reduceHalf(const LinearImage& src, bool halveX, bool halveY) {
  LinearImage dst;
  dst.width = halveX ? (src.width + 1) / 2 : src.width;
  dst.height = halveY ? (src.height + 1) / 2 : src.height;
  dst.rgba.resize(size_t(dst.width) * dst.height * 4);
  tbb::parallel_for(tbb::blocked_range<uint32_t>(0, dst.height, 16), [&](const tbb::blocked_range<uint32_t>& rows) {
    for (uint32_t y = rows.begin(); y != rows.end(); ++y) {
      const size_t y0 = halveY ? 2 * y : y, y1 = halveY ? std::min(2 * y + 1, src.height - 1) : y;
      for (uint32_t x = 0; x < dst.width; ++x) {
        const size_t x0 = halveX ? 2 * x : x, x1 = halveX ? std::min(2 * x + 1, src.width - 1) : x;
        const float* a = &src.rgba[(y0 * src.width + x0) * 4];
        const float* b = &src.rgba[(y0 * src.width + x1) * 4];
        const float* c = &src.rgba[(y1 * src.width + x0) * 4];
        const float* d = &src.rgba[(y1 * src.width + x1) * 4];
        float* out = &dst.rgba[(size_t(y) * dst.width + x) * 4];
        for (int k = 0; k < 4; ++k) out[k] = 0.25f * ((a[k] + b[k]) + (c[k] + d[k]));
      }
    }
  });
  return dst;
}

// Appends the RGBA8 levels no wider than baked->size of the chain that starts at `level` (buildMipChain's
// values). Only two float levels exist at a time: levels above the baked size are averaged, then dropped.
void appendMips(LinearImage level, ColorSpace colorSpace, BakedImage* baked) {
  while (true) {
    if (level.width <= baked->size) baked->mips.push_back(encodeRgba8(level, colorSpace));
    if (level.width <= 1) break;
    level = halveLinear(level);
  }
}

}  // namespace

Result<LinearImage> decodeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace,
                                uint64_t maxPixels) {
  Result<DecodedImage> decoded = decodeImageForBake(bytes, size, name, colorSpace, maxPixels);
  if (!decoded) return decoded.error();
  if (decoded->codes.empty()) return std::move(decoded->linear);
  return linearFromCodes(decoded->codes, decoded->width, decoded->height, colorSpace);
}

Result<BakedImage> bakeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace,
                             uint32_t maxTextureSize, uint64_t maxPixels) {
  Result<DecodedImage> decoded = decodeImageForBake(bytes, size, name, colorSpace, maxPixels);
  if (!decoded) return decoded.error();
  return bakeDecodedImage(std::move(decoded.value()), name, colorSpace, maxTextureSize);
}

Result<BakedImage> bakeDecodedImage(DecodedImage decodedImage, const std::string& name, ColorSpace colorSpace,
                                    uint32_t maxTextureSize) {
  DecodedImage* decoded = &decodedImage;
  BakedImage baked;
  const uint32_t width = decoded->width, height = decoded->height;
  baked.originalWidth = width;
  baked.originalHeight = height;
  baked.size = bakedTextureSize(width, height, maxTextureSize);
  const bool squarePow2 = width == height && std::has_single_bit(width);
  if (squarePow2 && !decoded->codes.empty()) {
    // 8-bit square power of two: mip 0 is the file's own codes (encodeRgba8 of their linear values gives every
    // code back, TextureMath.EightBitCodesSurviveTheLinearRoundTrip), level 1 is averaged from them directly.
    if (baked.size < width) {
      baked.resizeNote =
          fmt::format("{}x{} -> {}x{} (size cap: top mip levels dropped)", width, height, baked.size, baked.size);
    }
    LinearImage level1 = width > 1 ? halveCodes(decoded->codes, width, colorSpace) : LinearImage{};
    if (width <= baked.size) baked.mips.push_back(std::move(decoded->codes));
    std::vector<uint8_t>().swap(decoded->codes);
    if (width > 1) appendMips(std::move(level1), colorSpace, &baked);
    return baked;
  }
  LinearImage image = decoded->codes.empty() ? std::move(decoded->linear)
                                             : linearFromCodes(decoded->codes, width, height, colorSpace);
  std::vector<uint8_t>().swap(decoded->codes);  // float from here: the codes would only add 4 B/pixel
  if (!squarePow2) {
    const char* why = width != height ? "non-square: square of the nearest power of two"
                      : baked.size < bakedTextureSize(width, height, kMaxTextureSize)
                          ? "size cap"
                          : "non-power-of-two: nearest power of two";
    baked.resizeNote = fmt::format("{}x{} -> {}x{} ({})", width, height, baked.size, baked.size, why);
    // A downscale by 2 or more is first box-halved per axis (as mips are) while the half stays >= the baked
    // size: the filter then spans under 2 source texels per output texel, and the resize costs O(S^2), not
    // O(S^2 * ratio^2) (8192 x 8191 to 2048 took over a minute).
    while (true) {
      const bool hx = (image.width + 1) / 2 >= baked.size, hy = (image.height + 1) / 2 >= baked.size;
      if (!hx && !hy) break;
      image = reduceHalf(image, hx, hy);
    }
    if (image.width != baked.size || image.height != baked.size) {
      Result<LinearImage> resized = resizeImage(image, baked.size, baked.size);
      if (!resized) return makeError(resized.error().code, name + ": " + resized.error().message);
      image = std::move(resized.value());
    }
  } else if (baked.size < width) {
    baked.resizeNote =
        fmt::format("{}x{} -> {}x{} (size cap: top mip levels dropped)", width, height, baked.size, baked.size);
  }
  appendMips(std::move(image), colorSpace, &baked);
  return baked;
}

}  // namespace visbuf
