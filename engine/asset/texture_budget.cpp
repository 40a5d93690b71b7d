// External image files, image headers, the memory estimate of one image's bake and the gate over it (contracts in texture_decode.h).
#include <algorithm>
#include <cstring>

#include <fmt/format.h>

#include "visbuf/asset/texture_decode.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"

namespace visbuf {

namespace {

uint32_t be32(const uint8_t* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

Error malformed(const std::string& name, const std::string& why) {
  return makeError(ErrorCode::MalformedInput, name + ": " + why);
}

// OpenImageIO 2.4's ImageInput::read_image reads through a buffer of up to 64 MiB of native pixels.
constexpr uint64_t kOiioReadBuffer = uint64_t{64} << 20;

}  // namespace

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

Result<ImageHeader> readImageHeader(const uint8_t* bytes, size_t size, const std::string& name) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  ImageHeader h;
  if (bytes == nullptr || size == 0) return malformed(name, "image data is empty");
  if (size >= 8 && std::memcmp(bytes, kPng, 8) == 0) {
    h.format = ImageFormat::Png;
    // Signature, then IHDR: length 13, type, width, height, bit depth, colour type, compression, filter,
    // interlace (PNG specification, 11.2.2). libpng checks the values and the CRC again when it decodes.
    if (size < 8 + 8 + 13 || be32(bytes + 8) != 13 || std::memcmp(bytes + 12, "IHDR", 4) != 0)
      return malformed(name, "truncated or corrupt image: PNG: the first chunk is not a 13-byte IHDR");
    h.width = be32(bytes + 16);
    h.height = be32(bytes + 20);
    h.bitDepth = bytes[24];
    h.interlaced = bytes[28] != 0;
  } else if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) {
    h.format = ImageFormat::Jpeg;
    bool frame = false;
    walkJpegMarkers(bytes, size, [&](uint8_t marker, size_t, size_t at, size_t length) {
      // SOF0-15 except DHT (C4), JPG (C8), DAC (CC): length, precision, height, width, components.
      const bool sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
      if (!sof || frame || length < 8 || at + 8 > size) return;
      frame = true;
      h.bitDepth = bytes[at + 2];
      h.height = uint32_t(bytes[at + 3]) << 8 | bytes[at + 4];
      h.width = uint32_t(bytes[at + 5]) << 8 | bytes[at + 6];
      h.components = bytes[at + 7];
      h.progressive = (marker & 0x03) == 0x02;  // C2, C6, CA, CE
    });
    if (!frame) return malformed(name, "truncated or corrupt image: JPEG: no frame header before the first scan");
  } else {
    return malformed(name, "not a PNG or JPEG file (unrecognised signature)");
  }
  if (h.width == 0 || h.height == 0) return malformed(name, "image has no pixels (a side of 0 in its header)");
  return h;
}

uint64_t imageBakePeakBytes(const ImageHeader& header, uint32_t maxTextureSize) {
  const uint64_t pixels = uint64_t(header.width) * header.height;
  uint64_t decode = 0;
  if (header.format == ImageFormat::Png) {
    decode = pixels * (header.bitDepth == 16 ? 16 : 4);
  } else {
    decode = pixels * 4 + kOiioReadBuffer;
    if (header.progressive) {
      const uint64_t padded = (uint64_t(header.width) + 15) / 16 * 16 * ((uint64_t(header.height) + 15) / 16 * 16);
      decode += padded * 2 * std::max<uint32_t>(header.components, 1);
    }
  }
  const uint64_t side = bakedTextureSize(header.width, header.height, maxTextureSize);
  return std::max(decode, pixels * 20) + side * side * 24;
}

void ImageMemoryGate::acquire(uint64_t bytes) {
  std::unique_lock<std::mutex> lock(mutex_);
  released_.wait(lock, [&] { return held_ == 0 || held_ + bytes <= budget_; });
  held_ += bytes;
}

void ImageMemoryGate::release(uint64_t bytes) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    held_ -= bytes;
  }
  released_.notify_all();
}

}  // namespace visbuf
