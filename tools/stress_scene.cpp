// The stress cases' scene helpers (stress_scene.h).
#include "stress_scene.h"

namespace visbuf::tools::stress {

MeshSource triangleSoup(const std::string& name, const std::vector<glm::vec3>& corners) {
  MeshSource m;
  m.name = name;
  for (size_t i = 0; i + 2 < corners.size(); i += 3) {
    const glm::vec3 n = glm::normalize(glm::cross(corners[i + 1] - corners[i], corners[i + 2] - corners[i]));
    for (int k = 0; k < 3; ++k) {
      m.positions.push_back(corners[i + size_t(k)]);
      m.normals.push_back(n);
      m.uvs.push_back(glm::vec2(k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f));
      m.indices.push_back(uint32_t(m.positions.size() - 1));
    }
  }
  return m;
}

Result<Scene> sceneOf(const std::string& name, const std::vector<MeshSource>& sources,
                      const std::vector<std::pair<uint32_t, glm::dmat4>>& objects, const Camera& camera) {
  Scene s;
  s.name = name;
  MeshBuildOptions single;
  single.maxLods = 1;  // the cases compare LOD 0 only
  for (const MeshSource& src : sources) {
    auto mesh = buildMesh(src, single);
    if (!mesh) return mesh.error();
    s.meshes.push_back(std::move(*mesh));
  }
  Material m;
  m.name = "stress";
  m.baseColor = glm::vec4(0.8f, 0.8f, 0.8f, 1.0f);
  s.materials.push_back(m);
  for (const auto& [mesh, transform] : objects) s.objects.push_back({transform, mesh, 0});
  s.defaultCamera = camera;
  return s;
}

Camera lookFrom(glm::dvec3 position, glm::dvec3 target, double nearPlane) {
  Camera c;
  c.position = position;
  c.target = target;
  c.nearPlane = nearPlane;
  return c;
}

Result<Rendered> renderOnce(gpu::Device& device, const Scene& scene, const Camera& camera, uint32_t w, uint32_t h,
                            bool attributes, RendererConfig config, SwRasterMode swRaster) {
  config.width = w;
  config.height = h;
  auto r = Renderer::create(device, scene, config);
  if (!r) return r.error();
  FrameOptions fo;
  fo.readIds = true;
  fo.readAttributes = attributes;
  fo.lodErrorPixels = 0.0f;
  fo.swRaster = swRaster;
  auto f = (*r)->renderFrame(camera, fo);
  if (!f) return f.error();
  return Rendered{std::move(*r), std::move(*f)};
}

size_t coveredPixels(const FrameResult& f) {
  size_t n = 0;
  for (size_t i = 0; i < f.ids.size(); i += 2) n += f.ids[i] != 0;
  return n;
}

void appendValues(StressRow& row, const nlohmann::ordered_json& values) {
  for (auto it = values.begin(); it != values.end(); ++it) row.values[it.key()] = it.value();
}

StressRow errorRow(const std::string& label, const Error& e) {
  return {{{"case", label}, {"error", e.message}, {"pass", false}}};
}

}  // namespace visbuf::tools::stress
