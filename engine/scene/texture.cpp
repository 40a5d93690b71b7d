#include "visbuf/scene/texture.h"

#include <algorithm>
#include <bit>

namespace visbuf {

uint32_t TextureClass::mipCountFor(uint32_t size) { return size == 0 ? 0 : uint32_t(std::bit_width(size)); }

uint64_t TextureClass::layerBytes(uint32_t mip) const {
  const uint64_t side = std::max<uint64_t>(uint64_t{size} >> mip, 1);
  return side * side * 4;
}

uint64_t TextureClass::offset(uint32_t mip, uint32_t layer) const {
  uint64_t at = 0;
  for (uint32_t m = 0; m < mip; ++m) at += layerBytes(m) * layers;
  return at + layerBytes(mip) * layer;
}

uint64_t TextureClass::totalBytes() const { return offset(mipCount, 0); }

}  // namespace visbuf
