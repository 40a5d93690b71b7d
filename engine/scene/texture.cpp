#include "visbuf/scene/texture.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>

namespace visbuf {

uint32_t TextureClass::mipCountFor(uint32_t size) { return size == 0 ? 0 : uint32_t(std::bit_width(size)); }

const char* textureFormatName(TextureFormat format) {
  switch (format) {
    case TextureFormat::Rgba8: return "rgba8";
    case TextureFormat::Bc1: return "bc1";
    case TextureFormat::Bc3: return "bc3";
    case TextureFormat::Bc4: return "bc4";
    case TextureFormat::Bc5: return "bc5";
  }
  return "unknown";
}

bool isBlockCompressed(TextureFormat format) { return format != TextureFormat::Rgba8; }

uint32_t textureFormatUnitBytes(TextureFormat format) {
  switch (format) {
    case TextureFormat::Rgba8: return 4;
    case TextureFormat::Bc1:
    case TextureFormat::Bc4: return 8;
    case TextureFormat::Bc3:
    case TextureFormat::Bc5: return 16;
  }
  return 0;
}

uint64_t textureImageBytes(TextureFormat format, uint32_t width, uint32_t height) {
  if (!isBlockCompressed(format)) return uint64_t{width} * height * 4;
  const uint64_t bx = (uint64_t{width} + 3) / 4, by = (uint64_t{height} + 3) / 4;
  return bx * by * textureFormatUnitBytes(format);
}

namespace {

// Block decoding in units of 1/255. exact: the palette as the Vulkan spec defines it (endpoints expanded and
// interpolated without rounding, as a GPU's float decode gives it); else rounded to 8 bits at each step
// (round half up: the expansion, then the interpolation).
double round8(double v, bool exact) { return exact ? v : std::floor(v + 0.5); }

// One BC4 block (8 bytes: two 8-bit endpoints, 16 3-bit indices) into channel `channel` of 16 RGBA texels.
void decodeBc4Block(const uint8_t* block, double* texels, int channel, bool exact) {
  const double a = block[0], b = block[1];
  double value[8] = {a, b, 0, 0, 0, 0, 0, 0};
  if (a > b) {
    for (int i = 1; i < 7; ++i) value[i + 1] = round8(((7 - i) * a + i * b) / 7.0, exact);
  } else {
    for (int i = 1; i < 5; ++i) value[i + 1] = round8(((5 - i) * a + i * b) / 5.0, exact);
    value[6] = 0;
    value[7] = 255;
  }
  uint64_t bits = 0;
  for (int i = 0; i < 6; ++i) bits |= uint64_t{block[2 + i]} << (8 * i);
  for (int i = 0; i < 16; ++i) texels[i * 4 + channel] = value[(bits >> (3 * i)) & 7];
}

// One BC1 colour block (8 bytes: two RGB565 endpoints, 16 2-bit indices) into RGB of 16 RGBA texels. `threeColour`
// allows BC1's 3-colour mode (endpoint 0 <= endpoint 1: midpoint and black); BC3's colour block is always 4-colour.
void decodeColourBlock(const uint8_t* block, double* texels, bool threeColour, bool exact) {
  const uint32_t e0 = uint32_t(block[0]) | uint32_t(block[1]) << 8, e1 = uint32_t(block[2]) | uint32_t(block[3]) << 8;
  double colour[4][3];
  for (int k = 0; k < 2; ++k) {
    const uint32_t e = k == 0 ? e0 : e1;
    colour[k][0] = round8(((e >> 11) & 31) * 255.0 / 31.0, exact);
    colour[k][1] = round8(((e >> 5) & 63) * 255.0 / 63.0, exact);
    colour[k][2] = round8((e & 31) * 255.0 / 31.0, exact);
  }
  for (int c = 0; c < 3; ++c) {
    if (!threeColour || e0 > e1) {
      colour[2][c] = round8((2.0 * colour[0][c] + colour[1][c]) / 3.0, exact);
      colour[3][c] = round8((colour[0][c] + 2.0 * colour[1][c]) / 3.0, exact);
    } else {
      colour[2][c] = round8((colour[0][c] + colour[1][c]) / 2.0, exact);
      colour[3][c] = 0;
    }
  }
  const uint32_t bits = uint32_t(block[4]) | uint32_t(block[5]) << 8 | uint32_t(block[6]) << 16 | uint32_t(block[7]) << 24;
  for (int i = 0; i < 16; ++i)
    for (int c = 0; c < 3; ++c) texels[i * 4 + c] = colour[(bits >> (2 * i)) & 3][c];
}

// RGBA per texel in units of 1/255 (see above).
std::vector<double> decodeBlocks(const uint8_t* data, uint32_t width, uint32_t height, TextureFormat format,
                                 bool exact) {
  std::vector<double> out(size_t(width) * height * 4);
  if (!isBlockCompressed(format)) {
    std::copy(data, data + out.size(), out.begin());
    return out;
  }
  const uint32_t unit = textureFormatUnitBytes(format);
  const uint32_t bx = (width + 3) / 4, by = (height + 3) / 4;
  double texels[16 * 4];
  for (uint32_t row = 0; row < by; ++row) {
    for (uint32_t col = 0; col < bx; ++col) {
      const uint8_t* block = &data[(size_t(row) * bx + col) * unit];
      std::fill(std::begin(texels), std::end(texels), 0.0);
      for (int i = 0; i < 16; ++i) texels[i * 4 + 3] = 255.0;
      switch (format) {
        case TextureFormat::Bc1: decodeColourBlock(block, texels, true, exact); break;
        case TextureFormat::Bc3:
          decodeBc4Block(block, texels, 3, exact);  // BC3's alpha block is a BC4 block
          decodeColourBlock(block + 8, texels, false, exact);
          break;
        case TextureFormat::Bc4: decodeBc4Block(block, texels, 0, exact); break;
        case TextureFormat::Bc5:
          decodeBc4Block(block, texels, 0, exact);
          decodeBc4Block(block + 8, texels, 1, exact);
          break;
        case TextureFormat::Rgba8: break;
      }
      for (uint32_t y = 0; y < 4 && row * 4 + y < height; ++y) {
        const uint32_t columns = std::min(4u, width - col * 4);
        std::copy(&texels[y * 16], &texels[y * 16 + columns * 4], &out[(size_t(row * 4 + y) * width + col * 4) * 4]);
      }
    }
  }
  return out;
}

}  // namespace

std::vector<uint8_t> decodeTextureImage(const uint8_t* data, uint32_t width, uint32_t height, TextureFormat format) {
  const std::vector<double> texels = decodeBlocks(data, width, height, format, false);
  return std::vector<uint8_t>(texels.begin(), texels.end());  // (whole numbers in [0, 255])
}

std::vector<double> decodeTextureImageExact(const uint8_t* data, uint32_t width, uint32_t height,
                                            TextureFormat format) {
  std::vector<double> texels = decodeBlocks(data, width, height, format, true);
  for (double& t : texels) t /= 255.0;
  return texels;
}

uint64_t TextureClass::layerBytes(uint32_t mip) const {
  const uint32_t side = mipSize(mip);
  return textureImageBytes(format, side, side);
}

uint64_t TextureClass::offset(uint32_t mip, uint32_t layer) const {
  uint64_t at = 0;
  for (uint32_t m = 0; m < mip; ++m) at += layerBytes(m) * layers;
  return at + layerBytes(mip) * layer;
}

uint64_t TextureClass::totalBytes() const { return offset(mipCount, 0); }

}  // namespace visbuf
