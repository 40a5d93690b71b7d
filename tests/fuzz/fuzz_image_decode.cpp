// libFuzzer target: the texture decoders (engine/asset/texture_bake.h: decodeImage through OpenImageIO, PNG and
// JPEG) and the rest of one image's bake (resize to a power of two, mip chain, RGBA8 encoding) on arbitrary
// bytes. Any input must give an image or an Error with a message.
//
// Pixel budget: the decoder checks the header's width x height against maxPixels before decoding; the default
// (64 Mpixel, 1 GiB of float RGBA) is more than the fuzzer's -rss_limit_mb allows with ASan, so a small
// budget is passed here. libpng / libjpeg themselves are not instrumented: coverage counts visbuf's code and
// OpenImageIO's inline headers only, and ASan sees their memory accesses only through its interceptors.
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "fuzz_check.h"
#include "visbuf/asset/texture_bake.h"

// LeakSanitizer: OpenImageIO 2.4's PNG reader loses the std::string of ImageInput::geterror() on a short read (a
// truncated PNG): PNGInput::PngReadCallback takes the message, then png_error() longjmps past its destructor.
// That is inside OpenImageIO, not fixable in visbuf (tests/unit/test_textures.cpp suppresses it too).
extern "C" const char* __lsan_default_suppressions() { return "leak:OpenImageIO_v2_4::ImageInput::geterror\n"; }

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
  for (size_t m = 0; m < baked->mips.size(); ++m) {
    const size_t side = std::max<size_t>(baked->size >> m, 1);
    VISBUF_FUZZ_CHECK(baked->mips[m].size() == side * side * 4, "bakeImage: mip level of the wrong size");
  }
  return 0;
}
