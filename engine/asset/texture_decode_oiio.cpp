// Image decoding and resampling for texture baking, through OpenImageIO (texture_bake.h).
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstring>
#include <optional>
#include <vector>

#include "visbuf/asset/texture_bake.h"

namespace visbuf {

namespace {

constexpr int kMaxSide = 16384;

Error malformed(const std::string& name, const std::string& why) {
  return makeError(ErrorCode::MalformedInput, name + ": " + why);
}

// The OpenImageIO reader for the bytes' signature (embedded images have no file name to go by).
const char* formatName(const uint8_t* bytes, size_t size) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (size >= 8 && std::memcmp(bytes, kPng, 8) == 0) return "png";
  if (size >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF) return "jpeg";
  return nullptr;
}

// Expands 1-4 decoded channels to RGBA (grey -> RGB, missing alpha -> 1) and linearises sRGB colour.
void expandToRgba(const std::vector<float>& in, int channels, ColorSpace colorSpace, std::vector<float>* out) {
  const size_t pixels = in.size() / size_t(channels);
  out->resize(pixels * 4);
  for (size_t p = 0; p < pixels; ++p) {
    const float* src = &in[p * size_t(channels)];
    float* dst = &(*out)[p * 4];
    const bool grey = channels <= 2;
    for (int c = 0; c < 3; ++c) dst[c] = grey ? src[0] : src[c];
    dst[3] = channels == 2 ? src[1] : channels == 4 ? src[3] : 1.0f;
    for (int c = 0; c < 4; ++c) dst[c] = std::clamp(dst[c], 0.0f, 1.0f);
    if (colorSpace == ColorSpace::Srgb)
      for (int c = 0; c < 3; ++c) dst[c] = srgbToLinear(dst[c]);
  }
}

// 1-4 channels of 8-bit codes to RGBA codes (grey -> RGB, missing alpha -> 255). Rows in parallel.
void expandCodes(const std::vector<uint8_t>& in, int channels, std::vector<uint8_t>* out) {
  const size_t pixels = in.size() / size_t(channels);
  out->resize(pixels * 4);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p != r.end(); ++p) {
      const uint8_t* src = &in[p * size_t(channels)];
      uint8_t* dst = &(*out)[p * 4];
      const bool grey = channels <= 2;
      for (int c = 0; c < 3; ++c) dst[c] = grey ? src[0] : src[c];
      dst[3] = channels == 2 ? src[1] : channels == 4 ? src[3] : 255;
    }
  });
}

// The reader's error message. OpenImageIO 2.4 keeps pending errors per ImageInput in a per-thread map, and
// errors raised while the reader closes would outlive it there (LeakSanitizer reports them): close
// explicitly, then drain.
std::string readerError(OIIO::ImageInput* in) {
  if (!in) return OIIO::geterror();
  std::string message = in->geterror();
  in->close();
  (void)in->geterror();
  return message;
}

// The budgets of decodeImage(), from a declared size: the pixel budget, then the side limit.
std::optional<Error> overBudget(const std::string& name, uint64_t width, uint64_t height, uint64_t maxPixels) {
  const uint64_t pixels = width * height;
  if (pixels > maxPixels) {
    return makeError(ErrorCode::CapacityExceeded,
                     name + ": " + std::to_string(width) + "x" + std::to_string(height) + " = " +
                         std::to_string(pixels) + " pixels exceeds the image pixel budget of " +
                         std::to_string(maxPixels) + " (raise it with --max-image-pixels)");
  }
  if (width > uint64_t(kMaxSide) || height > uint64_t(kMaxSide)) {
    return makeError(ErrorCode::CapacityExceeded, name + ": " + std::to_string(width) + "x" +
                                                      std::to_string(height) + " exceeds the " +
                                                      std::to_string(kMaxSide) + "-texel side limit");
  }
  return std::nullopt;
}

// A JPEG as decodeImage() hands it to OpenImageIO, and the frame size its header declares.
struct PreparedJpeg {
  std::vector<uint8_t> bytes;      // the file, metadata segments relabelled (below)
  bool hasFrame = false;           // a frame header (SOFn) comes before the first scan
  uint32_t width = 0, height = 0;  // as that frame header declares them
};

// Two workarounds for OpenImageIO 2.4 (Debian 12), both found by tests/fuzz/fuzz_image_decode:
//  - It trusts the sizes inside JPEG metadata: a Photoshop / IPTC block (APP13) whose resource or dataset
//    length runs past its segment makes JpgInput::open() read past the end of a heap buffer (decode_iptc_iim;
//    fixed upstream in OpenImageIO 3.1). A texture needs no metadata, so APP1..APP13 (Exif, XMP, ICC profile,
//    Photoshop / IPTC, ...) are relabelled APP15, which libjpeg skips unread and OpenImageIO does not parse.
//    APP0 (JFIF) and APP14 (Adobe: the colour transform) stay.
//  - JpgInput::open() already starts decompressing, and for a progressive JPEG libjpeg then allocates the
//    coefficients of the whole declared frame (a 381-byte file declaring 52232 x 16392 took 2.6 GB and 7 s),
//    before the budgets below open() could refuse it. The declared size is read here, so the budgets are
//    checked before OpenImageIO sees the file.
// Markers are walked as libjpeg walks them (stray and fill bytes skipped, a length below 2 skips the length
// only) up to the first scan; anything malformed is left to libjpeg to report.
PreparedJpeg prepareJpeg(const uint8_t* bytes, size_t size) {
  PreparedJpeg out;
  out.bytes.assign(bytes, bytes + size);
  std::vector<uint8_t>& b = out.bytes;
  size_t i = 2;  // after SOI
  while (i < b.size()) {
    while (i < b.size() && b[i] != 0xFF) ++i;  // stray bytes
    while (i < b.size() && b[i] == 0xFF) ++i;  // fill bytes
    if (i >= b.size()) break;
    const uint8_t marker = b[i++];
    if (marker == 0x00 || marker == 0x01 || marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7)) continue;
    if (marker == 0xDA || marker == 0xD9) break;  // start of scan, end of image
    if (i + 2 > b.size()) break;
    const size_t length = size_t(b[i]) << 8 | b[i + 1];
    if (marker >= 0xE1 && marker <= 0xED) b[i - 1] = 0xEF;
    const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (frame && !out.hasFrame && length >= 7 && i + 7 <= b.size()) {  // length, precision, height, width
      out.hasFrame = true;
      out.height = uint32_t(b[i + 3]) << 8 | b[i + 4];
      out.width = uint32_t(b[i + 5]) << 8 | b[i + 6];
    }
    i += std::max<size_t>(length, 2);
  }
  return out;
}

}  // namespace

Result<DecodedImage> decodeImageForBake(const uint8_t* bytes, size_t size, const std::string& name,
                                        ColorSpace colorSpace, uint64_t maxPixels) {
  if (bytes == nullptr || size == 0) return malformed(name, "image data is empty");
  const char* format = formatName(bytes, size);
  if (!format) return malformed(name, "not a PNG or JPEG file (unrecognised signature)");
  PreparedJpeg jpeg;  // JPEG: metadata hidden and the declared size checked first (prepareJpeg)
  if (std::strcmp(format, "jpeg") == 0) {
    jpeg = prepareJpeg(bytes, size);
    bytes = jpeg.bytes.data();
    if (jpeg.hasFrame) {
      if (std::optional<Error> over = overBudget(name, jpeg.width, jpeg.height, maxPixels)) return *over;
    }
  }
  OIIO::Filesystem::IOMemReader reader(bytes, size);
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);  // glTF alpha is straight: do not premultiply
  // create + set_ioproxy + open: OpenImageIO 2.4's open(name, config, proxy) loses the proxy when given a
  // config and then looks for a file.
  auto in = OIIO::ImageInput::create(format);
  OIIO::ImageSpec spec;
  if (!in || !in->set_ioproxy(&reader) || !in->open(name, spec, config))
    return malformed(name, "cannot decode: " + readerError(in.get()));
  if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1)
    return malformed(name, "image has no pixels");
  // Budgets, from the header alone: nothing below is allocated for an image that fails them.
  const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
  if (std::optional<Error> over = overBudget(name, uint64_t(spec.width), uint64_t(spec.height), maxPixels)) {
    (void)readerError(in.get());
    return *over;
  }
  const int channels = std::min(spec.nchannels, 4);
  // 8-bit files (every JPEG, most PNGs) are read as bytes and kept as codes (DecodedImage).
  const bool bytes8 = spec.format == OIIO::TypeDesc::UINT8;
  std::vector<float> decoded;
  std::vector<uint8_t> decoded8;
  try {
    if (bytes8)
      decoded8.resize(size_t(pixels) * size_t(channels));
    else
      decoded.resize(size_t(pixels) * size_t(channels));
  } catch (const std::bad_alloc&) {
    (void)readerError(in.get());
    return makeError(ErrorCode::CapacityExceeded, name + ": out of memory decoding " + std::to_string(spec.width) +
                                                      "x" + std::to_string(spec.height) + " pixels");
  }
  if (!in->read_image(0, 0, 0, channels, bytes8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT,
                      bytes8 ? static_cast<void*>(decoded8.data()) : static_cast<void*>(decoded.data())))
    return malformed(name, "cannot decode: " + readerError(in.get()));
  // A truncated or corrupt stream can still "succeed": libjpeg pads a truncated JPEG with grey and only
  // warns ("Premature end of JPEG file"), which OpenImageIO keeps as a pending error. Any such message means
  // the pixels are not the file's: refuse rather than bake half an image.
  if (std::string pending = readerError(in.get()); !pending.empty()) {
    while (!pending.empty() && (pending.back() == '\n' || pending.back() == ' ')) pending.pop_back();
    return malformed(name, "truncated or corrupt image: " + pending);
  }
  DecodedImage image;
  image.width = uint32_t(spec.width);
  image.height = uint32_t(spec.height);
  if (bytes8) {
    expandCodes(decoded8, channels, &image.codes);
  } else {
    image.linear.width = image.width;
    image.linear.height = image.height;
    expandToRgba(decoded, channels, colorSpace, &image.linear.rgba);
  }
  return image;
}

Result<LinearImage> resizeImage(const LinearImage& image, uint32_t width, uint32_t height) {
  OIIO::ImageBuf src(OIIO::ImageSpec(int(image.width), int(image.height), 4, OIIO::TypeDesc::FLOAT),
                     const_cast<float*>(image.rgba.data()));  // wrapped read-only: resize never writes src
  OIIO::ImageBuf dst(OIIO::ImageSpec(int(width), int(height), 4, OIIO::TypeDesc::FLOAT));
  if (!OIIO::ImageBufAlgo::resize(dst, src))
    return makeError(ErrorCode::MalformedInput, "image resize failed: " + dst.geterror());
  LinearImage out;
  out.width = width;
  out.height = height;
  out.rgba.resize(size_t(width) * height * 4);
  if (!dst.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::FLOAT, out.rgba.data()))
    return makeError(ErrorCode::MalformedInput, "image resize failed: " + dst.geterror());
  for (float& v : out.rgba) v = std::clamp(v, 0.0f, 1.0f);  // the resampling filter rings past [0,1]
  return out;
}

}  // namespace visbuf
