// PNG decoding for texture baking, straight through libpng (texture_decode.h says why not OpenImageIO).
//
// What libpng is allowed to see and do:
//  - Only IHDR, PLTE, tRNS, IDAT and IEND are read. Every other chunk (text: tEXt / zTXt / iTXt, which carry
//    XMP; eXIf; iCCP; gAMA, sRGB, cHRM, ...; private chunks) is skipped unread
//    (png_set_keep_unknown_chunks(NEVER, all)): a texture needs none of them, and nothing parses them, so no
//    metadata can reach a recursive parser (an XMP of 20,000 nested elements overflowed OpenImageIO's stack).
//    Skipped chunks are not even decompressed; their CRCs are not checked.
//  - libpng's errors and warnings go to handlers here, never to stderr: an error ends the decode with its
//    message in visbuf's Error; warnings (benign by libpng's own judgement, e.g. extra compressed data after
//    the last row) are dropped.
//  - Rows are decoded one at a time (interlaced images pass by pass, each pass's rows scattered to their
//    place) straight into the output: 8-bit files into RGBA8 codes (4 bytes a pixel), 16-bit files into float
//    RGBA (16 bytes a pixel). Nothing else of image size is allocated (kPngDecodeBytesPerPixel*).
#include <png.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstring>
#include <new>
#include <vector>

#include "visbuf/asset/texture_decode.h"

namespace visbuf {

namespace {

// The decode's state, shared with libpng's callbacks (a plain struct: longjmp skips no destructor of it).
struct PngJob {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;
  char message[200] = {};  // libpng's error, when one ended the decode
  // Output (exactly one set): RGBA8 codes or linear float RGBA, width x height.
  uint8_t* codes = nullptr;
  float* linear = nullptr;
  const float* colourTable = nullptr;  // 16-bit code -> linear value of R, G, B (alpha: code / 65535)
  uint8_t* row = nullptr;              // one decoded row: width x 4 channels x (1 or 2) bytes
  uint32_t width = 0, height = 0;
};

[[noreturn]] void onError(png_structp png, png_const_charp message) {
  auto* job = static_cast<PngJob*>(png_get_error_ptr(png));
  std::snprintf(job->message, sizeof(job->message), "%s", message ? message : "unknown libpng error");
  png_longjmp(png, 1);
}

void onWarning(png_structp, png_const_charp) {}  // benign by libpng's judgement; never printed (see above)

void onRead(png_structp png, png_bytep out, size_t count) {
  auto* job = static_cast<PngJob*>(png_get_io_ptr(png));
  if (count > job->size - job->pos) png_error(png, "file ends early (truncated PNG)");
  std::memcpy(out, job->data + job->pos, count);
  job->pos += count;
}

// Stores decoded row pixels [0, count) of one pass at x = x0, x0 + dx, ... of image row y.
void storeRow(const PngJob& job, uint32_t y, uint32_t x0, uint32_t dx, uint32_t count) {
  if (job.codes) {
    uint8_t* dst = job.codes + (size_t(y) * job.width + x0) * 4;
    if (dx == 1) {
      std::memcpy(dst, job.row, size_t(count) * 4);
      return;
    }
    for (uint32_t i = 0; i < count; ++i) std::memcpy(dst + size_t(i) * dx * 4, job.row + size_t(i) * 4, 4);
    return;
  }
  float* dst = job.linear + (size_t(y) * job.width + x0) * 4;
  for (uint32_t i = 0; i < count; ++i) {
    const uint8_t* s = job.row + size_t(i) * 8;
    float* d = dst + size_t(i) * dx * 4;
    for (int c = 0; c < 3; ++c) d[c] = job.colourTable[size_t(s[2 * c]) << 8 | s[2 * c + 1]];
    d[3] = float(uint32_t(s[6]) << 8 | s[7]) * (1.0f / 65535.0f);
  }
}

// The libpng part: no C++ object with a destructor lives in this frame (longjmp comes back here).
bool runPng(PngJob* job, png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;  // NOLINT(cert-err52-cpp): libpng's error protocol
  png_set_read_fn(png, job, onRead);
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, nullptr, -1);  // all but IHDR PLTE tRNS IDAT IEND
  png_set_user_limits(png, kMaxImageSide, kMaxImageSide);
  png_set_chunk_malloc_max(png, 1u << 20);  // PLTE / tRNS are at most 768 bytes; nothing else is kept
  png_read_info(png, info);
  const int depth = png_get_bit_depth(png, info);
  const int type = png_get_color_type(png, info);
  const bool interlaced = png_get_interlace_type(png, info) != PNG_INTERLACE_NONE;
  // Everything to RGBA of 8 or 16 bits: palette -> RGB, grey below 8 bits -> 8, tRNS -> alpha, grey -> RGB,
  // no alpha -> opaque alpha. 16-bit samples stay big-endian (storeRow).
  png_set_expand(png);
  png_set_gray_to_rgb(png);
  const bool alpha = (type & PNG_COLOR_MASK_ALPHA) != 0 || png_get_valid(png, info, PNG_INFO_tRNS) != 0;
  if (!alpha) png_set_filler(png, depth == 16 ? 0xFFFF : 0xFF, PNG_FILLER_AFTER);
  png_read_update_info(png, info);
  if (png_get_channels(png, info) != 4 || png_get_bit_depth(png, info) != (depth == 16 ? 16 : 8) ||
      png_get_rowbytes(png, info) != size_t(job->width) * (depth == 16 ? 8 : 4)) {
    png_error(png, "unexpected row layout after expansion");
  }
  // Without png_set_interlace_handling an Adam7 file's rows come pass by pass, each pass's row holding only
  // its own pixels; libpng skips empty passes, as the loop does.
  const int passes = interlaced ? 7 : 1;
  for (int pass = 0; pass < passes; ++pass) {
    const uint32_t cols = interlaced ? PNG_PASS_COLS(job->width, pass) : job->width;
    const uint32_t rows = interlaced ? PNG_PASS_ROWS(job->height, pass) : job->height;
    if (cols == 0 || rows == 0) continue;
    for (uint32_t r = 0; r < rows; ++r) {
      const uint32_t y = interlaced ? PNG_ROW_FROM_PASS_ROW(r, pass) : r;
      if (job->codes && !interlaced) {  // 8-bit rows land in place
        png_read_row(png, job->codes + size_t(y) * job->width * 4, nullptr);
        continue;
      }
      png_read_row(png, job->row, nullptr);
      const uint32_t x0 = interlaced ? PNG_COL_FROM_PASS_COL(0, pass) : 0;
      const uint32_t dx = interlaced ? 1u << PNG_PASS_COL_SHIFT(pass) : 1;
      storeRow(*job, y, x0, dx, cols);
    }
  }
  png_read_end(png, nullptr);  // up to IEND: a file cut after its last row is still refused
  return true;
}

// 16-bit code -> linear value: code / 65535 (as OpenImageIO converts), then srgbToLinear for sRGB colour.
const std::vector<float>& colourTable16(bool srgb) {
  static const std::array<std::vector<float>, 2> kTables = [] {
    std::array<std::vector<float>, 2> t;
    for (int s = 0; s < 2; ++s) {
      t[size_t(s)].resize(65536);
      for (uint32_t k = 0; k < 65536; ++k) {
        const float v = float(k) * (1.0f / 65535.0f);
        t[size_t(s)][k] = s ? srgbToLinear(v) : std::clamp(v, 0.0f, 1.0f);
      }
    }
    return t;
  }();
  return kTables[srgb ? 1 : 0];
}

}  // namespace

Result<DecodedImage> decodePng(const uint8_t* bytes, size_t size, const ImageHeader& header, const std::string& name,
                               ColorSpace colorSpace) {
  DecodedImage image;
  image.width = header.width;
  image.height = header.height;
  const size_t pixels = size_t(header.width) * header.height;
  const bool deep = header.bitDepth == 16;
  std::vector<uint8_t> row;
  try {
    row.resize(size_t(header.width) * 8);
    if (deep) {
      image.linear.width = header.width;
      image.linear.height = header.height;
      image.linear.rgba.resize(pixels * 4);
    } else {
      image.codes.resize(pixels * 4);
    }
  } catch (const std::bad_alloc&) {
    return makeError(ErrorCode::CapacityExceeded, name + ": out of memory decoding " + std::to_string(header.width) +
                                                      "x" + std::to_string(header.height) + " pixels");
  }
  PngJob job;
  job.data = bytes;
  job.size = size;
  job.codes = deep ? nullptr : image.codes.data();
  job.linear = deep ? image.linear.rgba.data() : nullptr;
  job.colourTable = colourTable16(colorSpace == ColorSpace::Srgb).data();
  job.row = row.data();
  job.width = header.width;
  job.height = header.height;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &job, onError, onWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(png ? &png : nullptr, nullptr, nullptr);
    return makeError(ErrorCode::CapacityExceeded, name + ": out of memory starting the PNG decoder");
  }
  const bool ok = runPng(&job, png, info);
  png_destroy_read_struct(&png, &info, nullptr);
  if (!ok) return makeError(ErrorCode::MalformedInput, name + ": truncated or corrupt image: PNG: " + job.message);
  return image;
}

}  // namespace visbuf
