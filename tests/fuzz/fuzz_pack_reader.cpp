// libFuzzer target: parsePack() (engine/asset/pack_reader.h) on arbitrary bytes. The reader promises an Error
// (never a crash, an out-of-bounds read or an allocation larger than 64 times the file plus the zstd sections'
// decoded size, which the budget below bounds) for any damaged input, and a scene that passes validateScene() for
// any input it accepts. Zstd sections (the seeds' "texels") are checked and decoded like every other section.
//
// Every section and the header + section table carry a CRC-32, so nearly every mutation would stop at a
// checksum and never reach the record checks behind it. Each input is therefore parsed twice: as it is (the
// checksum and framing checks), and, when it has the pack magic, with every CRC that can be computed within
// the input rewritten to match (the record checks).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include "fuzz_check.h"
#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/scene/scene.h"

namespace {

void parse(const uint8_t* data, size_t size) {
  // A budget under libFuzzer's memory limit: a few bytes of zstd frames may honestly decode to gigabytes.
  visbuf::PackReadOptions options;
  options.maxDecodedBytes = uint64_t{256} << 20;
  visbuf::Result<visbuf::Scene> scene = visbuf::parsePack(data, size, "fuzz.vbp", options);
  if (!scene) {
    VISBUF_FUZZ_CHECK(!scene.error().message.empty(), "parsePack: error without a message");
    return;
  }
  const visbuf::Status valid = visbuf::validateScene(*scene);
  if (!valid) std::fprintf(stderr, "validateScene: %s\n", valid.error().message.c_str());
  VISBUF_FUZZ_CHECK(valid.ok(), "parsePack accepted a scene that fails validateScene()");
}

// Rewrites the section CRCs and the header CRC of a pack-like input where they lie within it. Returns false
// when nothing could be fixed (not a pack, or a header / table past the end).
bool fixChecksums(std::vector<uint8_t>& v) {
  using namespace visbuf::pack;
  if (v.size() < sizeof(Header) || std::memcmp(v.data(), kMagic, 4) != 0) return false;
  Header h;
  std::memcpy(&h, v.data(), sizeof h);
  const uint64_t count = std::min<uint64_t>(h.sectionCount, kMaxSections);
  const uint64_t tableEnd = sizeof(Header) + count * sizeof(SectionEntry);
  if (tableEnd > v.size()) return false;
  for (uint64_t i = 0; i < count; ++i) {
    uint8_t* at = v.data() + sizeof(Header) + i * sizeof(SectionEntry);
    SectionEntry e;
    std::memcpy(&e, at, sizeof e);
    if (e.offset > v.size() || e.storedSize > v.size() - e.offset) continue;
    e.crc32 = crc32(v.data() + e.offset, size_t(e.storedSize));
    std::memcpy(at, &e, sizeof e);
  }
  Header zeroed = h;
  zeroed.headerCrc = 0;
  h.headerCrc = crc32(v.data() + sizeof(Header), size_t(tableEnd - sizeof(Header)), crc32(&zeroed, sizeof zeroed));
  std::memcpy(v.data(), &h, sizeof h);
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  parse(data, size);
  std::vector<uint8_t> fixed(data, data + size);
  if (fixChecksums(fixed) && std::memcmp(fixed.data(), data, size) != 0) parse(fixed.data(), size);
  return 0;
}
