// Image files through OpenImageIO. Writes are atomic: a temporary file in the same folder, then rename.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/core/temp_file.h"  // commitFile: every write ends there

namespace visbuf {

// Writes linear RGBA float pixels. .png: 8-bit sRGB-encoded; .exr/.tif: 16/32-bit float linear.
Status writeColorImage(const std::string& path, uint32_t width, uint32_t height, const std::vector<float>& rgba);
// Writes 8-bit RGBA texels exactly as given (R first, straight alpha, no colour conversion); .png or .jpg.
Status writeRgba8Image(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba);
// Writes a two-channel 32-bit unsigned TIFF (object ID + 1, triangle index).
Status writeIdImage(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint32_t>& ids);
// Reads a two-channel uint32 TIFF written by writeIdImage.
Status readIdImage(const std::string& path, uint32_t& width, uint32_t& height, std::vector<uint32_t>& ids);

}  // namespace visbuf
