#include "scene_options.h"

#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include "asset/gltf_import.h"
#include "scene/generate.h"

namespace visbuf::tools {

void addSceneOptions(CLI::App& app, SceneOptions& o) {
  app.add_option("--scene", o.scene, "field | city | a .gltf/.glb file")->capture_default_str();
  app.add_option("--objects,--instances", o.objects, "number of objects (field: instances; city: approx. total)");
  app.add_option("--seed", o.seed, "scene generator seed")->capture_default_str();
  app.add_option("--mesh", o.mesh, "field: .gltf/.glb mesh to instance (default: procedural torus knot)");
}

namespace {
Result<MeshSource> importMesh(const std::string& path) {
  GltfImportReport report;
  Result<MeshSource> m = importGltfMesh(path, {}, &report);
  for (const std::string& w : report.warnings) std::fprintf(stderr, "visbuf: warning: %s\n", w.c_str());
  return m;
}
}  // namespace

Result<Scene> loadScene(const SceneOptions& o) {
  if (o.scene == "field") {
    FieldParams p;
    if (o.objects) p.objects = o.objects;
    p.seed = o.seed;
    if (!o.mesh.empty()) {
      Result<MeshSource> m = importMesh(o.mesh);
      if (!m) return m.error();
      p.mesh = std::move(m.value());
    }
    return makeFieldScene(p);
  }
  if (!o.mesh.empty()) return makeError(ErrorCode::InvalidArgument, "--mesh applies to --scene field only");
  if (o.scene == "city") {
    CityParams p;
    if (o.objects) p.objects = o.objects;
    p.seed = o.seed;
    return makeCityScene(p);
  }
  // A glTF file: its default scene flattened into one mesh, instanced once (or --instances times
  // in the field layout).
  Result<MeshSource> m = importMesh(o.scene);
  if (!m) return m.error();
  if (o.objects > 1) {
    FieldParams p;
    p.objects = o.objects;
    p.seed = o.seed;
    p.mesh = std::move(m.value());
    return makeFieldScene(p);
  }
  Result<Mesh> mesh = buildMesh(m.value());
  if (!mesh) return mesh.error();
  Scene scene;
  scene.name = o.scene;
  glm::vec4 s = mesh->boundsSphere;
  scene.meshes.push_back(std::move(mesh.value()));
  scene.materials.push_back({"default", glm::vec4(0.8f, 0.8f, 0.8f, 1.0f)});
  scene.objects.push_back({glm::dmat4(1.0), 0, 0});
  // Frame the whole object: distance so the bounding sphere fits the vertical field of view.
  double dist = double(s.w) / std::sin(glm::radians(60.0) * 0.5) * 1.05;
  scene.defaultCamera.target = glm::dvec3(glm::vec3(s));
  scene.defaultCamera.position = scene.defaultCamera.target + glm::normalize(glm::dvec3(0.35, 0.3, 1.0)) * dist;
  scene.defaultCamera.nearPlane = std::max(1e-4, double(s.w) * 1e-3);
  return scene;
}

void addCameraOptions(CLI::App& app, CameraOptions& o) {
  app.add_option("--camera-pos", o.position, "camera position x y z (default: the scene's)")->expected(3)->delimiter(',');
  app.add_option("--camera-target", o.target, "point the camera looks at x y z")->expected(3)->delimiter(',');
  app.add_option("--fov", o.fovDegrees, "vertical field of view in degrees")->capture_default_str();
  app.add_option("--near", o.nearPlane, "near plane distance (reverse-Z, infinite far)");
}

Result<Camera> makeCamera(const CameraOptions& o, const Scene& scene) {
  Camera c = scene.defaultCamera;
  if (!o.position.empty()) c.position = {o.position[0], o.position[1], o.position[2]};
  if (!o.target.empty()) c.target = {o.target[0], o.target[1], o.target[2]};
  if (!(o.fovDegrees > 0.0 && o.fovDegrees < 179.0))
    return makeError(ErrorCode::InvalidArgument, fmt::format("--fov {}: must be in (0, 179) degrees", o.fovDegrees));
  c.fovY = glm::radians(o.fovDegrees);
  if (o.nearPlane < 0.0 || !std::isfinite(o.nearPlane))
    return makeError(ErrorCode::InvalidArgument, "--near must be a positive distance");
  if (o.nearPlane > 0.0) c.nearPlane = o.nearPlane;
  return c;
}

Result<std::pair<uint32_t, uint32_t>> parseSize(const std::string& text) {
  unsigned w = 0, h = 0;
  char extra = 0;
  if (std::sscanf(text.c_str(), "%ux%u%c", &w, &h, &extra) != 2 || w == 0 || h == 0 || w > 16384 || h > 16384)
    return makeError(ErrorCode::InvalidArgument, fmt::format("--size '{}': expected WxH, each 1..16384", text));
  return std::pair{uint32_t(w), uint32_t(h)};
}

}  // namespace visbuf::tools
