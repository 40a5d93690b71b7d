#include "visbuf/core/image_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <unistd.h>

namespace visbuf {

namespace {

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

std::string tempPathFor(const std::string& path) {
  std::filesystem::path p(path);
  // Keep the extension last so OpenImageIO picks the right writer.
  return (p.parent_path() / fmt::format(".{}.tmp{}{}", p.stem().string(), getpid(), p.extension().string())).string();
}

float linearToSrgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

Status writeWith(const std::string& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc dataType, const void* data) {
  const std::string tmp = tempPathFor(path);
  auto out = OIIO::ImageOutput::create(tmp);
  if (!out) return makeError(ErrorCode::IoError, fmt::format("{}: no image writer for this extension ({})", path, OIIO::geterror()));
  if (!out->open(tmp, spec) || !out->write_image(dataType, data) || !out->close()) {
    std::string err = out->geterror();
    std::remove(tmp.c_str());
    return makeError(ErrorCode::IoError, fmt::format("{}: write failed: {}", path, err));
  }
  return commitFile(tmp, path);
}

}  // namespace

Status writeColorImage(const std::string& path, uint32_t width, uint32_t height, const std::vector<float>& rgba) {
  if (rgba.size() != size_t(width) * height * 4) return makeError(ErrorCode::InvalidArgument, "colour image size mismatch");
  const std::string ext = extensionOf(path);
  if (ext == ".exr" || ext == ".tif" || ext == ".tiff") {
    OIIO::ImageSpec spec(int(width), int(height), 4, ext == ".exr" ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    return writeWith(path, spec, OIIO::TypeDesc::FLOAT, rgba.data());  // converted to the file's format
  }
  if (ext != ".png" && ext != ".jpg" && ext != ".jpeg")
    return makeError(ErrorCode::InvalidArgument, fmt::format("{}: output must be .png, .exr or .tif", path));
  std::vector<uint8_t> px(rgba.size());
  for (size_t i = 0; i < rgba.size(); ++i) {
    float v = (i % 4 == 3) ? std::clamp(rgba[i], 0.0f, 1.0f) : linearToSrgb(rgba[i]);
    px[i] = uint8_t(std::lround(v * 255.0f));
  }
  OIIO::ImageSpec spec(int(width), int(height), 4, OIIO::TypeDesc::UINT8);
  return writeWith(path, spec, OIIO::TypeDesc::UINT8, px.data());
}

Status writeRgba8Image(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
  if (rgba.size() != size_t(width) * height * 4) return makeError(ErrorCode::InvalidArgument, "RGBA8 image size mismatch");
  OIIO::ImageSpec spec(int(width), int(height), 4, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // the texels are straight alpha: write them unchanged
  return writeWith(path, spec, OIIO::TypeDesc::UINT8, rgba.data());
}

Status writeIdImage(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint32_t>& ids) {
  if (ids.size() != size_t(width) * height * 2) return makeError(ErrorCode::InvalidArgument, "ID image size mismatch");
  const std::string ext = extensionOf(path);
  if (ext != ".tif" && ext != ".tiff") return makeError(ErrorCode::InvalidArgument, fmt::format("{}: ID output must be .tif", path));
  OIIO::ImageSpec spec(int(width), int(height), 2, OIIO::TypeDesc::UINT32);
  spec.channelnames = {"object", "triangle"};
  return writeWith(path, spec, OIIO::TypeDesc::UINT32, ids.data());
}

Status readIdImage(const std::string& path, uint32_t& width, uint32_t& height, std::vector<uint32_t>& ids) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return makeError(ErrorCode::FileNotFound, fmt::format("{}: {}", path, OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.nchannels != 2) return makeError(ErrorCode::MalformedInput, fmt::format("{}: expected 2 channels", path));
  width = uint32_t(spec.width);
  height = uint32_t(spec.height);
  ids.resize(size_t(width) * height * 2);
  if (!in->read_image(0, 0, 0, 2, OIIO::TypeDesc::UINT32, ids.data()))
    return makeError(ErrorCode::MalformedInput, fmt::format("{}: {}", path, in->geterror()));
  return {};
}

}  // namespace visbuf
