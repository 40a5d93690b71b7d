// Image I/O for builds without OpenImageIO (-DVISBUF_WITH_OIIO=OFF, used to carry a self-contained
// binary to a GPU machine): every call fails with a message saying so; nothing is written.
#include "visbuf/core/image_io.h"

#include <filesystem>

namespace visbuf {

namespace {
Error unavailable(const std::string& path) {
  return makeError(ErrorCode::Unsupported, path + ": this build has no OpenImageIO (VISBUF_WITH_OIIO=OFF)");
}
}  // namespace

Status writeColorImage(const std::string& path, uint32_t, uint32_t, const std::vector<float>&) { return unavailable(path); }
Status writeRgba8Image(const std::string& path, uint32_t, uint32_t, const std::vector<uint8_t>&) { return unavailable(path); }
Status writeIdImage(const std::string& path, uint32_t, uint32_t, const std::vector<uint32_t>&) { return unavailable(path); }
Status readIdImage(const std::string& path, uint32_t&, uint32_t&, std::vector<uint32_t>&) { return unavailable(path); }

}  // namespace visbuf
