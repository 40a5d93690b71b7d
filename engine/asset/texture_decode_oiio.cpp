// Image decoding and resampling for texture baking, through OpenImageIO (texture_bake.h).
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstring>

#include "asset/texture_bake.h"

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

}  // namespace

Result<LinearImage> decodeImage(const uint8_t* bytes, size_t size, const std::string& name, ColorSpace colorSpace) {
  if (bytes == nullptr || size == 0) return malformed(name, "image data is empty");
  const char* format = formatName(bytes, size);
  if (!format) return malformed(name, "not a PNG or JPEG file (unrecognised signature)");
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
  if (spec.width > kMaxSide || spec.height > kMaxSide) {
    return makeError(ErrorCode::CapacityExceeded, name + ": " + std::to_string(spec.width) + "x" +
                                                      std::to_string(spec.height) + " exceeds the " +
                                                      std::to_string(kMaxSide) + "-texel side limit");
  }
  const int channels = std::min(spec.nchannels, 4);
  std::vector<float> decoded(size_t(spec.width) * size_t(spec.height) * size_t(channels));
  if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, decoded.data()))
    return malformed(name, "cannot decode: " + readerError(in.get()));
  LinearImage image;
  image.width = uint32_t(spec.width);
  image.height = uint32_t(spec.height);
  expandToRgba(decoded, channels, colorSpace, &image.rgba);
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
