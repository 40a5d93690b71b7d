// Texture baking: size rule, mip chains, sRGB encoding, size classes (contract in texture_bake.h). Decoding and
// resampling live in texture_decode_oiio.cpp (texture_decode_none.cpp without OpenImageIO).
#include "visbuf/asset/texture_bake.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <utility>

#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"

namespace visbuf {

namespace {

constexpr uint32_t kMaxTextureSize = 16384;
constexpr uint32_t kMaxLayersPerClass = 256;  // Vulkan's guaranteed minimum of maxImageArrayLayers

// The linear value whose sRGB encoding lies halfway between codes k and k + 1 (k = 0..254): encodeSrgb8(v) =
// number of midpoints below v = round(255 * encode(v)), rounded in the encoded domain as GPUs and image tools do.
std::array<float, 255> makeSrgbMidpoints() {
  std::array<float, 255> mid{};
  auto decode = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  for (int k = 0; k < 255; ++k) mid[size_t(k)] = float(decode((k + 0.5) / 255.0));
  return mid;
}

// An external image: a regular file only, opened without blocking (core/file_read.h), within the size budget.
Result<std::vector<uint8_t>> readImageFile(const ImportedImage& image) {
  const std::string shown = quoteForMessage(image.name);
  uint64_t size = 0;
  const FileKind kind = probeFile(image.path, &size, /*noFollow=*/true);
  if (kind == FileKind::Missing) {
    return makeError(ErrorCode::FileNotFound, fmt::format("image '{}': file '{}' not found", shown, image.path));
  }
  if (kind != FileKind::Regular) {
    return makeError(ErrorCode::InvalidArgument, fmt::format("image '{}': '{}' is not a regular file ({}); only regular "
                                                          "files are read",
                                                          shown, image.path, fileKindName(kind)));
  }
  FileReadOptions options;
  options.maxBytes = kMaxImageFileBytes;
  options.noFollow = true;  // the importer's paths are link-free (uri_resolver.h): a link here was swapped in
  Result<std::vector<uint8_t>> bytes = readRegularFile(image.path, options);
  if (!bytes) return makeError(bytes.error().code, fmt::format("image '{}': {}", shown, bytes.error().message));
  return bytes;
}

// Numbers the (image, colour space) pairs in order of first use and points every reference at its number.
Result<std::vector<std::pair<int32_t, ColorSpace>>> assignTextures(const ImportedScene& imported, Scene* scene) {
  std::vector<std::pair<int32_t, ColorSpace>> keys;
  std::map<std::pair<int32_t, ColorSpace>, int32_t> index;
  for (Material& m : scene->materials) {
    const auto slots = textureSlots(m);
    for (size_t slot = 0; slot < slots.size(); ++slot) {
      TextureRef* ref = slots[slot];
      const ColorSpace colorSpace = textureSlotColorSpace(slot);
      if (ref->image < 0) continue;
      if (size_t(ref->image) >= imported.images.size()) {
        return makeError(ErrorCode::MalformedInput,
                         fmt::format("material '{}': image {} does not exist ({} images)", m.name, ref->image,
                                     imported.images.size()));
      }
      auto [it, added] = index.emplace(std::pair{ref->image, colorSpace}, int32_t(keys.size()));
      if (added) keys.emplace_back(ref->image, colorSpace);
      ref->baked = it->second;
    }
  }
  return keys;
}

// Puts each baked image into a class (layer = position in its class) and concatenates the texels mip-major.
void buildClasses(std::vector<BakedImage>& baked, Scene* scene) {
  std::map<std::pair<uint32_t, ColorSpace>, uint32_t> open;  // (size, colour space) -> class with room
  for (size_t t = 0; t < baked.size(); ++t) {
    Texture& texture = scene->textures[t];
    const auto key = std::pair{baked[t].size, texture.colorSpace};
    auto it = open.find(key);
    if (it == open.end() || scene->textureClasses[it->second].layers == kMaxLayersPerClass) {
      TextureClass c;
      c.size = baked[t].size;
      c.colorSpace = texture.colorSpace;
      c.mipCount = TextureClass::mipCountFor(c.size);
      scene->textureClasses.push_back(c);
      it = open.insert_or_assign(key, uint32_t(scene->textureClasses.size() - 1)).first;
    }
    texture.sizeClass = it->second;
    texture.layer = scene->textureClasses[it->second].layers++;
  }
  for (uint32_t c = 0; c < scene->textureClasses.size(); ++c) {
    TextureClass& cls = scene->textureClasses[c];
    cls.texels.reserve(cls.totalBytes());
    for (uint32_t mip = 0; mip < cls.mipCount; ++mip) {
      for (size_t t = 0; t < baked.size(); ++t) {
        if (scene->textures[t].sizeClass != c) continue;  // textures are in layer order within a class
        std::vector<uint8_t>& level = baked[t].mips[mip];
        cls.texels.insert(cls.texels.end(), level.begin(), level.end());
        std::vector<uint8_t>().swap(level);
      }
    }
  }
}

}  // namespace

float srgbToLinear(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

uint8_t encodeSrgb8(float linear) {
  static const std::array<float, 255> kMidpoints = makeSrgbMidpoints();
  if (!(linear > 0.0f)) return 0;  // also NaN
  return uint8_t(std::lower_bound(kMidpoints.begin(), kMidpoints.end(), linear) - kMidpoints.begin());
}

uint32_t bakedTextureSize(uint32_t width, uint32_t height, uint32_t maxSize) {
  const uint32_t side = std::max({width, height, 1u});
  const uint32_t lower = std::bit_floor(side);
  // Nearest power of two, ties up: side >= 1.5 * lower rounds up (64-bit: lower can be 2^31).
  const uint64_t nearest = uint64_t{side} * 2 >= uint64_t{lower} * 3 ? uint64_t{lower} * 2 : lower;
  return uint32_t(std::min<uint64_t>(nearest, std::max(maxSize, 1u)));
}

std::vector<LinearImage> buildMipChain(LinearImage level0) {
  std::vector<LinearImage> chain;
  chain.push_back(std::move(level0));
  while (chain.back().width > 1) {
    const LinearImage& src = chain.back();
    LinearImage dst;
    dst.width = dst.height = src.width / 2;
    dst.rgba.resize(size_t(dst.width) * dst.height * 4);
    for (uint32_t y = 0; y < dst.height; ++y) {
      for (uint32_t x = 0; x < dst.width; ++x) {
        const float* a = &src.rgba[(size_t(2 * y) * src.width + 2 * x) * 4];
        const float* b = a + size_t(src.width) * 4;  // the row below
        float* out = &dst.rgba[(size_t(y) * dst.width + x) * 4];
        for (int c = 0; c < 4; ++c) out[c] = 0.25f * ((a[c] + a[4 + c]) + (b[c] + b[4 + c]));
      }
    }
    chain.push_back(std::move(dst));
  }
  return chain;
}

std::vector<uint8_t> encodeRgba8(const LinearImage& image, ColorSpace colorSpace) {
  std::vector<uint8_t> out(image.rgba.size());
  for (size_t i = 0; i < image.rgba.size(); ++i) {
    const float v = image.rgba[i];
    const bool srgb = colorSpace == ColorSpace::Srgb && i % 4 != 3;  // alpha is always linear
    out[i] = srgb ? encodeSrgb8(v) : uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
  }
  return out;
}

Result<BakedImage> bakeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace,
                             uint32_t maxTextureSize, uint64_t maxPixels) {
  Result<LinearImage> decoded = decodeImage(bytes, size, name, colorSpace, maxPixels);
  if (!decoded) return decoded.error();
  BakedImage baked;
  baked.originalWidth = decoded->width;
  baked.originalHeight = decoded->height;
  baked.size = bakedTextureSize(decoded->width, decoded->height, maxTextureSize);
  const bool squarePow2 = decoded->width == decoded->height && std::has_single_bit(decoded->width);
  if (!squarePow2) {
    const char* why = decoded->width != decoded->height ? "non-square: square of the nearest power of two"
                      : baked.size < bakedTextureSize(decoded->width, decoded->height, kMaxTextureSize)
                          ? "size cap"
                          : "non-power-of-two: nearest power of two";
    baked.resizeNote = fmt::format("{}x{} -> {}x{} ({})", decoded->width, decoded->height, baked.size, baked.size, why);
    decoded = resizeImage(*decoded, baked.size, baked.size);
    if (!decoded) return makeError(decoded.error().code, name + ": " + decoded.error().message);
  } else if (baked.size < decoded->width) {
    baked.resizeNote = fmt::format("{}x{} -> {}x{} (size cap: top mip levels dropped)", decoded->width,
                                   decoded->height, baked.size, baked.size);
  }
  std::vector<LinearImage> chain = buildMipChain(std::move(decoded.value()));
  for (const LinearImage& level : chain) {
    if (level.width <= baked.size) baked.mips.push_back(encodeRgba8(level, colorSpace));
  }
  return baked;
}

Status bakeTextures(const ImportedScene& imported, const TextureBakeOptions& options, Scene* scene,
                    TextureBakeReport* report, const TextureBakeProgress& progress) {
  if (options.maxTextureSize < 1 || options.maxTextureSize > kMaxTextureSize ||
      !std::has_single_bit(options.maxTextureSize)) {
    return makeError(ErrorCode::InvalidArgument, fmt::format("maxTextureSize {} must be a power of two in [1, {}]",
                                                             options.maxTextureSize, kMaxTextureSize));
  }
  if (options.maxImagePixels < 1)
    return makeError(ErrorCode::InvalidArgument, "maxImagePixels must be at least 1");
  scene->textures.clear();
  scene->textureClasses.clear();
  auto keys = assignTextures(imported, scene);
  if (!keys) return keys.error();
  std::vector<BakedImage> baked;
  for (size_t t = 0; t < keys->size(); ++t) {
    const auto [imageIndex, colorSpace] = (*keys)[t];
    const ImportedImage& image = imported.images[size_t(imageIndex)];
    const std::string name =
        fmt::format("{}: image {} '{}'", quoteForMessage(imported.name), imageIndex, quoteForMessage(image.name));
    Result<std::vector<uint8_t>> file = image.path.empty() ? Result<std::vector<uint8_t>>(image.bytes)
                                                           : readImageFile(image);
    if (!file) return makeError(file.error().code, imported.name + ": " + file.error().message);
    Result<BakedImage> b =
        bakeImage(file->data(), file->size(), name, colorSpace, options.maxTextureSize, options.maxImagePixels);
    if (!b) return b.error();
    if (report && !b->resizeNote.empty()) report->notes.push_back(fmt::format("{}: {}", name, b->resizeNote));
    scene->textures.push_back({image.name, imageIndex, colorSpace, 0, 0, b->originalWidth, b->originalHeight});
    baked.push_back(std::move(b.value()));
    if (progress) progress(t + 1, keys->size(), image.name);
  }
  buildClasses(baked, scene);
  if (report) {
    report->texelBytes = 0;
    for (const TextureClass& c : scene->textureClasses) report->texelBytes += c.texels.size();
  }
  return {};
}

}  // namespace visbuf
