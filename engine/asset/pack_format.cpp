// CRC-32 for the pack format (pack_format.h), from zlib: its slicing implementation checks about ten times
// as many bytes per second as a byte-at-a-time table, and loading a large pack is dominated by the checksum.
#include "visbuf/asset/pack_format.h"

#include <zlib.h>

namespace visbuf::pack {

uint32_t crc32(const void* data, size_t size, uint32_t crc) {
  return static_cast<uint32_t>(::crc32_z(crc, static_cast<const Bytef*>(data), size));
}

}  // namespace visbuf::pack
