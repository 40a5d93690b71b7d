// Texture decoding for builds without OpenImageIO (-DVISBUF_WITH_OIIO=OFF): baking textures fails with a
// message saying so (bake with --no-textures, or on a machine with OpenImageIO).
#include "visbuf/asset/texture_bake.h"

namespace visbuf {

namespace {
Error unavailable(const std::string& name) {
  return makeError(ErrorCode::Unsupported,
                   name + ": cannot decode textures: this build has no OpenImageIO (VISBUF_WITH_OIIO=OFF); "
                          "bake with --no-textures");
}
}  // namespace

Result<DecodedImage> decodeImageForBake(const uint8_t*, size_t, const std::string& name, ColorSpace, uint64_t) {
  return unavailable(name);
}
Result<LinearImage> resizeImage(const LinearImage&, uint32_t, uint32_t) { return unavailable("resize"); }

}  // namespace visbuf
