// Image decoding and resampling for texture baking: PNG through libpng (texture_decode_png.cpp), JPEG and
// resampling through OpenImageIO (texture_bake.h, texture_decode.h).
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
#include "visbuf/asset/texture_decode.h"

namespace visbuf {

namespace {

Error malformed(const std::string& name, const std::string& why) {
  return makeError(ErrorCode::MalformedInput, name + ": " + why);
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
  if (width > uint64_t(kMaxImageSide) || height > uint64_t(kMaxImageSide)) {
    return makeError(ErrorCode::CapacityExceeded, name + ": " + std::to_string(width) + "x" +
                                                      std::to_string(height) + " exceeds the " +
                                                      std::to_string(kMaxImageSide) + "-texel side limit");
  }
  return std::nullopt;
}

// A JPEG as decodeJpeg hands it to OpenImageIO. Two workarounds for OpenImageIO 2.4 (Debian 12), both found by
// tests/fuzz/fuzz_image_decode:
//  - It trusts the sizes inside JPEG metadata: a Photoshop / IPTC block (APP13) whose resource or dataset
//    length runs past its segment makes JpgInput::open() read past the end of a heap buffer (decode_iptc_iim;
//    fixed upstream in OpenImageIO 3.1), and it parses XMP (APP1) with a recursive XML parser. A texture needs
//    no metadata, so APP1..APP13 (Exif, XMP, ICC profile, Photoshop / IPTC, ...) and comments (COM, which
//    OpenImageIO keeps in memory) are relabelled APP15, which libjpeg skips unread and OpenImageIO does not
//    parse. APP0 (JFIF) and APP14 (Adobe: the colour transform) stay.
//  - JpgInput::open() already starts decompressing, and for a progressive JPEG libjpeg then allocates the
//    coefficients of the whole declared frame (a 381-byte file declaring 52232 x 16392 took 2.6 GB and 7 s),
//    before the budgets below open() could refuse it: readImageHeader reads the declared size first.
// Anything malformed is left to libjpeg to report.
std::vector<uint8_t> prepareJpeg(const uint8_t* bytes, size_t size) {
  std::vector<uint8_t> b(bytes, bytes + size);
  walkJpegMarkers(b.data(), b.size(), [&](uint8_t marker, size_t markerAt, size_t, size_t) {
    if ((marker >= 0xE1 && marker <= 0xED) || marker == 0xFE) b[markerAt] = 0xEF;
  });
  return b;
}

// Sets the channels [channels, 4) of RGBA pixels whose first `channels` are decoded: grey -> RGB, missing
// alpha -> `one`. Rows in parallel.
template <class T>
void completeRgba(T* rgba, size_t pixels, int channels, T one) {
  if (channels == 4) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pixels, 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t p = r.begin(); p != r.end(); ++p) {
      T* px = rgba + p * 4;
      if (channels <= 2) px[3] = channels == 2 ? px[1] : one;
      if (channels <= 2) px[1] = px[2] = px[0];
      if (channels == 3) px[3] = one;
    }
  });
}

// A JPEG through OpenImageIO, read straight into the RGBA output (strided: no copy of image size besides
// OpenImageIO's own read buffer).
Result<DecodedImage> decodeJpeg(const uint8_t* original, size_t size, const ImageHeader& header,
                                const std::string& name, ColorSpace colorSpace) {
  const std::vector<uint8_t> bytes = prepareJpeg(original, size);
  OIIO::Filesystem::IOMemReader reader(bytes.data(), bytes.size());
  // create + set_ioproxy + open: OpenImageIO 2.4's open(name, config, proxy) loses the proxy when given a
  // config and then looks for a file.
  auto in = OIIO::ImageInput::create("jpeg");
  OIIO::ImageSpec spec, config;
  if (!in || !in->set_ioproxy(&reader) || !in->open(name, spec, config))
    return malformed(name, "cannot decode: " + readerError(in.get()));
  if (uint32_t(spec.width) != header.width || uint32_t(spec.height) != header.height || spec.nchannels < 1) {
    (void)readerError(in.get());
    return malformed(name, "cannot decode: the frame header and the decoder disagree on the size");
  }
  const int channels = std::min(spec.nchannels, 4);
  const size_t pixels = size_t(spec.width) * size_t(spec.height);
  const bool bytes8 = spec.format == OIIO::TypeDesc::UINT8;  // libjpeg-turbo: always, 8-bit samples
  DecodedImage image;
  image.width = header.width;
  image.height = header.height;
  try {
    if (bytes8) {
      image.codes.resize(pixels * 4);
    } else {
      image.linear.width = image.width;
      image.linear.height = image.height;
      image.linear.rgba.resize(pixels * 4);
    }
  } catch (const std::bad_alloc&) {
    (void)readerError(in.get());
    return makeError(ErrorCode::CapacityExceeded, name + ": out of memory decoding " + std::to_string(spec.width) +
                                                      "x" + std::to_string(spec.height) + " pixels");
  }
  const OIIO::stride_t pixelBytes = bytes8 ? 4 : 16;
  void* out = bytes8 ? static_cast<void*>(image.codes.data()) : static_cast<void*>(image.linear.rgba.data());
  if (!in->read_image(0, 0, 0, channels, bytes8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT, out, pixelBytes,
                      pixelBytes * spec.width))
    return malformed(name, "cannot decode: " + readerError(in.get()));
  // A truncated or corrupt stream can still "succeed": libjpeg pads a truncated JPEG with grey and only
  // warns ("Premature end of JPEG file"), which OpenImageIO keeps as a pending error. Any such message means
  // the pixels are not the file's: refuse rather than bake half an image.
  if (std::string pending = readerError(in.get()); !pending.empty()) {
    while (!pending.empty() && (pending.back() == '\n' || pending.back() == ' ')) pending.pop_back();
    return malformed(name, "truncated or corrupt image: " + pending);
  }
  if (bytes8) {
    completeRgba<uint8_t>(image.codes.data(), pixels, channels, 255);
  } else {
    float* v = image.linear.rgba.data();
    completeRgba<float>(v, pixels, channels, 1.0f);
    for (size_t i = 0; i < pixels * 4; ++i) {
      v[i] = std::clamp(v[i], 0.0f, 1.0f);
      if (colorSpace == ColorSpace::Srgb && i % 4 != 3) v[i] = srgbToLinear(v[i]);
    }
  }
  return image;
}

}  // namespace

Result<DecodedImage> decodeImageForBake(const uint8_t* bytes, size_t size, const std::string& name,
                                        ColorSpace colorSpace, uint64_t maxPixels) {
  Result<ImageHeader> header = readImageHeader(bytes, size, name);
  if (!header) return header.error();
  // Budgets, from the header alone: nothing of image size is allocated for an image that fails them.
  if (std::optional<Error> over = overBudget(name, header->width, header->height, maxPixels)) return *over;
  if (header->format == ImageFormat::Png) return decodePng(bytes, size, *header, name, colorSpace);
  return decodeJpeg(bytes, size, *header, name, colorSpace);
}

Result<LinearImage> resizeImage(const LinearImage& image, uint32_t width, uint32_t height) {
  LinearImage out;
  out.width = width;
  out.height = height;
  out.rgba.resize(size_t(width) * height * 4);
  // Both wrapped: resize reads src and writes straight into the output (no third copy of image size).
  OIIO::ImageBuf src(OIIO::ImageSpec(int(image.width), int(image.height), 4, OIIO::TypeDesc::FLOAT),
                     const_cast<float*>(image.rgba.data()));  // read-only: resize never writes src
  OIIO::ImageBuf dst(OIIO::ImageSpec(int(width), int(height), 4, OIIO::TypeDesc::FLOAT), out.rgba.data());
  if (!OIIO::ImageBufAlgo::resize(dst, src))
    return makeError(ErrorCode::MalformedInput, "image resize failed: " + dst.geterror());
  for (float& v : out.rgba) v = std::clamp(v, 0.0f, 1.0f);  // the resampling filter rings past [0,1]
  return out;
}

}  // namespace visbuf
