// Internal to the texture bake (texture_bake.cpp, texture_budget.cpp, texture_decode_*.cpp): what an encoded
// image's header declares, read from its bytes alone; the memory one image's decode and bake take at most,
// computed from that header before anything of image size is allocated; the gate that keeps the images baked
// at once within a memory budget; the decoders behind decodeImageForBake (texture_bake.h).
//
// Decoders: PNG through libpng directly (texture_decode_png.cpp), so that only the chunks a texture needs are
// read, libpng's messages become visbuf errors and rows land straight in the output; JPEG through OpenImageIO
// (texture_decode_oiio.cpp) after its metadata segments are relabelled.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

#include "visbuf/asset/texture_bake.h"
#include "visbuf/core/result.h"

namespace visbuf {

// Largest side of an image (either format): 16384, as Vulkan's maxImageDimension2D guarantees.
inline constexpr uint32_t kMaxImageSide = 16384;

enum class ImageFormat { Png, Jpeg };

struct ImageHeader {
  ImageFormat format = ImageFormat::Png;
  uint32_t width = 0, height = 0;
  uint32_t bitDepth = 8;     // PNG: IHDR's bit depth (1, 2, 4, 8, 16); JPEG: the frame's sample precision
  uint32_t components = 0;   // JPEG: the frame's colour components; PNG: 0
  bool progressive = false;  // JPEG: a progressive frame (SOF2 / 6 / 10 / 14): libjpeg keeps every coefficient
  bool interlaced = false;   // PNG: Adam7
};

// An external image's file (ImportedImage::path): a regular file only, opened without blocking and without
// following links (core/file_read.h), at most kMaxImageFileBytes.
Result<std::vector<uint8_t>> readImageFile(const ImportedImage& image);

// The header of a PNG (the IHDR that must be its first chunk) or a JPEG (the first frame header, SOFn, before
// the first scan). MalformedInput (with `name`) when the bytes are neither or the header is missing or cut.
Result<ImageHeader> readImageHeader(const uint8_t* bytes, size_t size, const std::string& name);

// Bytes of memory decoding and baking one image takes at most (what bakeTextures reserves, docs/security.md):
//   decode:  PNG 8-bit (any colour type, palette, interlaced): 4 B/pixel (RGBA8 codes, rows decoded in place);
//            PNG 16-bit: 16 B/pixel (float RGBA, rows converted as they are decoded);
//            JPEG: 4 B/pixel, plus 2 B per pixel and component for a progressive frame (libjpeg's coefficient
//            buffer, blocks rounded up to 16 pixels), plus OpenImageIO's 64 MiB read buffer;
//   bake:    20 B/pixel while 8-bit codes become float RGBA for resampling (16-bit: the float image and its
//            first mip level), then 24 B per texel of the baked S x S texture (the resampled image, its mip
//            chain in float and encoded).
// The estimate is max(decode, 20 B/pixel) + 24 B * S^2, S = bakedTextureSize(width, height, maxTextureSize).
uint64_t imageBakePeakBytes(const ImageHeader& header, uint32_t maxTextureSize);

// The images baked at once (bakeTextures bakes them in parallel) hold at most this many estimated bytes
// (imageBakePeakBytes) between them; an image whose estimate alone is larger runs with no other.
inline constexpr uint64_t kImageBakeMemoryBudget = uint64_t{1536} << 20;

// A counting gate over estimated bytes. acquire() waits while other reservations are held and this one would
// take the total past the budget; a reservation is always admitted when none is held (no deadlock, no refusal:
// the pixel budget is what refuses an image). Callers in oneTBB tasks must isolate the work done while holding
// (tbb::this_task_arena::isolate), so that a thread waiting inside nested parallelism never picks up another
// image's task and blocks on the gate it holds.
class ImageMemoryGate {
 public:
  explicit ImageMemoryGate(uint64_t budget) : budget_(budget) {}
  void acquire(uint64_t bytes);
  void release(uint64_t bytes);

 private:
  std::mutex mutex_;
  std::condition_variable released_;
  uint64_t held_ = 0;
  uint64_t budget_;
};

// Walks a JPEG's markers as libjpeg does (stray and fill bytes skipped, a length below 2 skips the length
// only) from after SOI up to the first scan (SOS) or EOI. visit(marker, markerAt, lengthAt, length): the marker
// code, the index of its code byte, the index of its 2-byte length and that length (0 when the bytes end
// inside it: then the walk stops after the call). Standalone markers (RSTn, TEM, a repeated SOI) are skipped.
template <class Visit>
void walkJpegMarkers(const uint8_t* b, size_t size, Visit&& visit) {
  size_t i = 2;  // after SOI
  while (i < size) {
    while (i < size && b[i] != 0xFF) ++i;  // stray bytes
    while (i < size && b[i] == 0xFF) ++i;  // fill bytes
    if (i >= size) break;
    const uint8_t marker = b[i++];
    if (marker == 0x00 || marker == 0x01 || marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7)) continue;
    if (marker == 0xDA || marker == 0xD9) break;  // start of scan, end of image
    if (i + 2 > size) {
      visit(marker, i - 1, i, size_t{0});
      break;
    }
    const size_t length = size_t(b[i]) << 8 | b[i + 1];
    visit(marker, i - 1, i, length);
    i += length < 2 ? 2 : length;
  }
}

// decodeImageForBake's decoders, given the header readImageHeader read from the same bytes (its budgets
// already checked). PNG: texture_decode_png.cpp.
Result<DecodedImage> decodePng(const uint8_t* bytes, size_t size, const ImageHeader& header, const std::string& name,
                               ColorSpace colorSpace);

}  // namespace visbuf
