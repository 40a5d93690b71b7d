// libFuzzer target: the texture decoders (engine/asset/texture_decode.h: PNG through libpng directly, JPEG
// through OpenImageIO after its metadata segments are relabelled) and the rest of one image's bake (resize to a
// power of two, mip chain, RGBA8 encoding) on arbitrary bytes. Any input must give an image or an Error with a
// message, print nothing (libpng's messages are routed into the Error), and stay within -timeout and
// -rss_limit_mb (scripts/fuzz.sh): a slow or hungry input is a finding.
//
// Pixel budget: the decoder checks the header's width x height against maxPixels before decoding; the default
// (64 Mpixel) is more than the fuzzer's -rss_limit_mb allows with ASan, so a small budget is passed here. The
// peak-memory estimate of each accepted image (imageBakePeakBytes) is checked to be consistent with it.
// libpng / libjpeg themselves are not instrumented: coverage counts visbuf's code and OpenImageIO's inline
// headers only, and ASan sees their memory accesses only through its interceptors.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "fuzz_check.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/asset/texture_decode.h"

namespace {

constexpr uint64_t kMaxPixels = 512 * 512;
constexpr uint32_t kMaxTextureSize = 64;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace visbuf;
  Result<BakedImage> baked = bakeImage(data, size, "fuzz", ColorSpace::Srgb, kMaxTextureSize, kMaxPixels);
  if (!baked) {
    VISBUF_FUZZ_CHECK(!baked.error().message.empty(), "bakeImage: error without a message");
    return 0;
  }
  VISBUF_FUZZ_CHECK(baked->size >= 1 && baked->size <= kMaxTextureSize, "bakeImage: size out of range");
  VISBUF_FUZZ_CHECK(uint64_t(baked->originalWidth) * baked->originalHeight <= kMaxPixels,
                    "bakeImage: decoded more pixels than the budget");
  VISBUF_FUZZ_CHECK(!baked->mips.empty(), "bakeImage: no mip levels");
  Result<ImageHeader> header = readImageHeader(data, size, "fuzz");
  VISBUF_FUZZ_CHECK(header && header->width == baked->originalWidth && header->height == baked->originalHeight,
                    "bakeImage: decoded a size other than the header's");
  VISBUF_FUZZ_CHECK(imageBakePeakBytes(*header, kMaxTextureSize) <= kMaxPixels * 20 + (uint64_t{64} << 20) +
                                                                       uint64_t{kMaxTextureSize} * kMaxTextureSize * 24 +
                                                                       kMaxPixels * 6,
                    "imageBakePeakBytes: estimate beyond the per-pixel bound");
  for (size_t m = 0; m < baked->mips.size(); ++m) {
    const size_t side = std::max<size_t>(baked->size >> m, 1);
    VISBUF_FUZZ_CHECK(baked->mips[m].size() == side * side * 4, "bakeImage: mip level of the wrong size");
  }
  return 0;
}
