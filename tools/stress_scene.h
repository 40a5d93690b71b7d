// The stress cases' shared scene helpers (tools/stress_scene.cpp) and the cases of tools/stress_limits.cpp (bad
// input, capacity, scale); tools/stress_cases.cpp holds the precision cases and the list `visbuf stress` runs.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "stress_cases.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/mesh.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools::stress {

// A mesh of separate triangles (no shared vertices), face normals, uv = (lambda1, lambda2) at each corner so
// interpolated uv errors are barycentric errors.
MeshSource triangleSoup(const std::string& name, const std::vector<glm::vec3>& corners);

// A scene of `sources` (LOD 0 only: the cases compare with references that know no LOD), one grey material, the
// objects (mesh index, transform) and `camera` as its default camera.
Result<Scene> sceneOf(const std::string& name, const std::vector<MeshSource>& sources,
                      const std::vector<std::pair<uint32_t, glm::dmat4>>& objects, const Camera& camera);

Camera lookFrom(glm::dvec3 position, glm::dvec3 target, double nearPlane = 0.1);

// Camera at the origin looking down -Z (up +Y), so object coordinates are camera coordinates.
inline const Camera kAtOrigin = lookFrom(glm::dvec3(0.0), glm::dvec3(0.0, 0.0, -1.0));

struct Rendered {
  std::unique_ptr<Renderer> renderer;
  FrameResult frame;
};

// Renders one frame of `scene` with LOD off and IDs (and optionally attributes) read back.
Result<Rendered> renderOnce(gpu::Device& device, const Scene& scene, const Camera& camera, uint32_t w, uint32_t h,
                            bool attributes, RendererConfig config = {}, SwRasterMode swRaster = SwRasterMode::Auto);

size_t coveredPixels(const FrameResult& f);
void appendValues(StressRow& row, const nlohmann::ordered_json& values);
// A failed row naming the error.
StressRow errorRow(const std::string& label, const Error& e);

// tools/stress_limits.cpp
StressCase badInput(const StressContext& ctx);
StressCase capacity(const StressContext& ctx);
StressCase scale(const StressContext& ctx);

}  // namespace visbuf::tools::stress
