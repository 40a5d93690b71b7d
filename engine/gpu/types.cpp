// Pins the sizes of the shared GPU structs (shaders/shared/types.h). A mismatch with the GLSL std430 /
// std140 layout would silently corrupt every pass, so it fails the build instead; the unit tests also
// compare member offsets with the ones glslang reflects.
#include <cstddef>

#include "visbuf/shared/types.h"

namespace visbuf::gpu {

static_assert(sizeof(Vertex) == 32);
static_assert(sizeof(LodData) == 16);
static_assert(sizeof(ClusterData) == 48);
static_assert(sizeof(VertexExtra) == 16);
static_assert(sizeof(MeshData) == 48 + 16 * MAX_LODS);
static_assert(sizeof(SkinnedVertex) == 16);
static_assert(sizeof(SkinInstance) == 64);
static_assert(sizeof(MorphDelta) == 36);
static_assert(sizeof(ObjectData) == 64, "per-object GPU data stays at 64 bytes");
static_assert(sizeof(TextureSlotData) == 48);
static_assert(sizeof(MaterialData) == 64 + 48 * TEXTURE_SLOTS);
static_assert(offsetof(MaterialData, textures) == 64);
static_assert(sizeof(DrawCommand) == 20, "VkDrawIndexedIndirectCommand layout");
static_assert(sizeof(FrameData) == 400 && offsetof(FrameData, projection) == 368);
static_assert(offsetof(FrameData, swRaster) == 320);
static_assert(offsetof(FrameData, view) == 64);
static_assert(offsetof(FrameData, cameraOffset) == 128);
static_assert(offsetof(FrameData, frustum) == 144);
static_assert(offsetof(FrameData, lightDir) == 224);
static_assert(offsetof(FrameData, lodScale) == 256);
static_assert(offsetof(FrameData, projX) == 288);
static_assert(sizeof(PointLightData) == 64 && offsetof(PointLightData, type) == 56);
static_assert(offsetof(FrameData, pointLightCount) == 308);
static_assert(sizeof(PassConstants) == 16);
static_assert(sizeof(MaterialTiles) == 32);
static_assert(offsetof(MaterialTiles, pixels) == 12, "the first three words are VkDispatchIndirectCommand");
static_assert(CLASSIFY_DISPATCH_WIDTH * 32768ull >= 2048ull * 2048ull, "the largest frame's tiles fit 32,768 rows");
static_assert(sizeof(PyramidConstants) == 32);
static_assert(offsetof(ObjectData, meshIndex) == 48);
static_assert(offsetof(MeshData, lods) == 48);

}  // namespace visbuf::gpu
