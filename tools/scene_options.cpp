#include "scene_options.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "cli_checks.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/core/file_read.h"
#include "visbuf/scene/generate.h"

namespace visbuf::tools {

void addSceneOptions(CLI::App& app, SceneOptions& o) {
  app.add_option("--scene", o.scene, "field | city | foliage | foliage-opaque | terrain | a .gltf/.glb file | a baked pack (.vbp, visbuf bake)")
      ->check(nonEmptyPath())
      ->capture_default_str();
  app.add_option("--objects,--instances", o.objects,
                 "number of objects (field: instances; city: approx. total; a glTF or a pack: copies of its scene on a "
                 "grid, with its materials, textures and lights, each animated at its own phase)")
      ->check(unsignedIn(1, UINT32_MAX));
  app.add_option("--seed", o.seed, "scene generator seed")->check(unsignedIn(0, UINT64_MAX))->capture_default_str();
  app.add_option("--terrain-size", o.terrainSize,
                 fmt::format("terrain: vertices per side of the heightfield, {}..{} (2 (N-1)^2 triangles; default {})",
                             kTerrainMinSize, kTerrainMaxSize, TerrainParams{}.size))
      ->check(unsignedIn(kTerrainMinSize, kTerrainMaxSize));
  app.add_option("--mesh", o.mesh, "field: .gltf/.glb mesh to instance (default: procedural torus knot)")
      ->check(nonEmptyPath());
  app.add_option("--lights", o.lights, "scatter N point lights over the scene (tiled light culling)")
      ->check(unsignedIn(0, UINT32_MAX));
  app.add_flag("--no-sun", o.noSun, "no directional light (ambient, emissive and point lights only)");
  app.add_option("--allow-uri-root", o.load.allowedUriRoots,
                 "glTF scenes: also let buffer / image uris point into this folder (repeatable; by default only "
                 "files inside the glTF's own folder are read: docs/security.md)")
      ->check(nonEmptyPath() & CLI::ExistingDirectory);
  app.add_option("--max-image-pixels", o.load.maxImagePixels,
                 "glTF scenes: refuse images whose header declares more pixels than this, before decoding")
      ->check(unsignedIn(1, uint64_t{1} << 40))
      ->capture_default_str();
  addImportBudgetOptions(app, o.load.maxInstances, o.load.maxImportMemory);
  addExtensionPolicyOptions(app, o.load.ignoreRequiredExtensions, o.load.strictImages);
  app.add_option("--materials", o.materials,
                 "field, city, foliage: replace the materials with N generated PBR materials (3 of 4 textured), "
                 "assigned to objects by hash (material classification's many-material scenes)")
      ->check(unsignedIn(0, UINT32_MAX));
  app.add_option("--object-order", o.objectOrder,
                 "spatial: number the objects along a Morton curve of their positions once the scene is built (the "
                 "same image, faster GPU-driven passes) | as-built: as the generator or the file made them")
      ->check(CLI::IsMember({"spatial", "as-built"}))
      ->capture_default_str();
}

void addImportBudgetOptions(CLI::App& app, uint64_t& maxInstances, uint64_t& maxImportMemory) {
  app.add_option("--max-instances", maxInstances,
                 "glTF: refuse a file whose mesh instances (nodes, EXT_mesh_gpu_instancing) pass this count, before "
                 "any instance is built")
      ->check(unsignedIn(1, uint64_t{1} << 32))
      ->capture_default_str();
  app.add_option("--max-import-memory", maxImportMemory,
                 "glTF: the import's memory budget in bytes (file, JSON, buffers, decoded accessors, output), "
                 "checked before each allocation; a pack: what its zstd sections may decode to")
      ->check(unsignedIn(uint64_t{1} << 20, uint64_t{1} << 40))
      ->capture_default_str();
}

void addExtensionPolicyOptions(CLI::App& app, std::vector<std::string>& ignoreRequired, bool& strictImages) {
  app.add_option("--ignore-required-extension", ignoreRequired,
                 "glTF: import a file that requires this extension although visbuf does not read it (repeatable; "
                 "'*': any), rendering it without the extension (warned); `visbuf extensions` lists what is read")
      ->check(nonEmptyPath());
  app.add_flag("--strict-images", strictImages,
               "glTF: fail when an image cannot be decoded (corrupt, missing, KTX2/WebP) instead of dropping its "
               "texture with a warning");
}

namespace {

void printWarnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::fprintf(stderr, "visbuf: warning: %s\n", printable(w).c_str());
}

Result<MeshSource> importMesh(const std::string& path, const SceneOptions& o) {
  // A pack holds built meshes with their LOD chains and materials, not a source mesh to instance: said plainly
  // rather than as the glTF parser's complaint about the pack's bytes.
  if (sceneFileKind(path) == SceneFileKind::Pack)
    return makeError(ErrorCode::InvalidArgument,
                     "--mesh '" + path + "': is a visbuf pack; --mesh takes a .gltf/.glb mesh (render a pack with "
                     "--scene '" + path + "', and --objects N for N copies of it)");
  GltfImportReport report;
  Result<MeshSource> m = importGltfMesh(path, gltfImportOptions(o.load), &report);
  printWarnings(report.warnings);
  return m;
}

ObjectOrder objectOrder(const SceneOptions& o) {
  return o.objectOrder == "spatial" ? ObjectOrder::Spatial : ObjectOrder::AsBuilt;
}

// A generated layout with --materials, in --object-order.
Result<Scene> makeLayout(const SceneOptions& o) {
  if (o.terrainSize != 0 && o.scene != "terrain")
    return makeError(ErrorCode::InvalidArgument, "--terrain-size applies to --scene terrain only");
  Result<Scene> scene = [&]() -> Result<Scene> {
    if (o.scene == "field") {
      FieldParams p;
      if (o.objects) p.objects = o.objects;
      p.seed = o.seed;
      if (!o.mesh.empty()) {
        Result<MeshSource> m = importMesh(o.mesh, o);
        if (!m) return m.error();
        p.mesh = std::move(m.value());
      }
      return makeFieldScene(p);
    }
    if (!o.mesh.empty()) return makeError(ErrorCode::InvalidArgument, "--mesh applies to --scene field only");
    if (o.scene == "terrain") {  // one heightfield mesh
      if (o.objects > 1)
        return makeError(ErrorCode::InvalidArgument,
                         "--objects: --scene terrain is one mesh (size it with --terrain-size)");
      TerrainParams p;
      if (o.terrainSize) p.size = o.terrainSize;
      p.seed = o.seed;
      return makeTerrainScene(p);
    }
    if (o.scene == "foliage" || o.scene == "foliage-opaque") {  // alpha-masked cards; the same cards opaque
      FoliageParams p;
      if (o.objects) p.cards = o.objects;
      p.seed = o.seed;
      p.masked = o.scene == "foliage";
      return makeFoliageScene(p);
    }
    CityParams p;
    if (o.objects) p.objects = o.objects;
    p.seed = o.seed;
    return makeCityScene(p);
  }();
  if (!scene) return scene;
  if (o.materials > 0)
    if (Status s = applyGeneratedMaterials(*scene, o.materials, o.seed); !s) return s.error();
  // Last, so that the materials above (placed by object index) are those of the layout as built.
  if (objectOrder(o) == ObjectOrder::Spatial) orderObjectsSpatially(*scene);
  return scene;
}

// A glTF or a pack, assembled by the engine (load_scene.h); --objects N > 1: N copies of the file's scene.
Result<Scene> loadFile(const SceneOptions& o) {
  if (!o.mesh.empty()) return makeError(ErrorCode::InvalidArgument, "--mesh applies to --scene field only");
  if (o.terrainSize != 0)
    return makeError(ErrorCode::InvalidArgument, "--terrain-size applies to --scene terrain only");
  if (o.materials > 0)
    return makeError(ErrorCode::InvalidArgument, "--materials applies to the generated layouts only (field, city, "
                                                 "foliage, foliage-opaque, terrain)");
  LoadOptions lo = o.load;
  lo.instances = std::max(o.objects, 1u);
  lo.seed = o.seed;
  lo.objectOrder = objectOrder(o);
  Result<LoadedScene> loaded = visbuf::loadScene(o.scene, lo);
  if (!loaded) return loaded.error();
  printWarnings(loaded->warnings);
  return std::move(loaded->scene);
}

}  // namespace

bool isLayoutName(const std::string& scene) {
  return scene == "field" || scene == "city" || scene == "foliage" || scene == "foliage-opaque" || scene == "terrain";
}

void noteSceneInputs(const SceneOptions& o) {
  if (!isLayoutName(o.scene)) noteInputFile(o.scene, "the --scene file");
  if (!o.mesh.empty()) noteInputFile(o.mesh, "the --mesh file");
}

Result<Scene> loadScene(const SceneOptions& o) {
  Result<Scene> scene = isLayoutName(o.scene) ? makeLayout(o) : loadFile(o);
  if (!scene) return scene;
  // Scattered lights are placed in the box of the objects' bounds, which does not depend on their order.
  scatterPointLights(*scene, o.lights, o.seed);
  if (o.noSun) scene->lightIntensity = 0.0f;
  return scene;
}

void addCameraOptions(CLI::App& app, CameraOptions& o) {
  app.add_option("--camera-pos", o.position, "camera position x y z (default: the scene's)")
      ->expected(3)
      ->delimiter(',')
      ->check(finiteNumber());
  app.add_option("--camera-target", o.target, "point the camera looks at x y z")
      ->expected(3)
      ->delimiter(',')
      ->check(finiteNumber());
  app.add_option("--camera", o.camera,
                 "start from a camera of the file: gltf (its first) or gltf:N; `--camera` alone or `--camera list` "
                 "lists them (default: a camera framing the scene over its whole animation)")
      ->expected(0, 1)
      ->default_str("list");
  app.add_option("--fov", o.fovDegrees, "vertical field of view in degrees, in (0, 179) (default: the camera's; 60 "
                                        "for the default camera)")
      ->check(finiteNumber(0.0, 179.0, true, true));
  app.add_option("--near", o.nearPlane, "near plane distance > 0 (reverse-Z; default: the camera's)")
      ->check(finiteNumber(0.0, std::numeric_limits<double>::infinity(), true));
}

bool camerasListRequested(const CameraOptions& o) { return o.camera == "list"; }

std::string describeCameras(const Scene& scene) {
  if (scene.cameras.empty()) return "the scene has no cameras\n";
  std::string out;
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    const Camera& c = scene.cameras[i].camera;
    std::string projection;
    const std::string far = std::isfinite(c.farPlane) ? fmt::format("{:g}", c.farPlane) : std::string("infinite");
    if (c.projection == Projection::Orthographic)
      projection = fmt::format("orthographic xmag {:g} ymag {:g} znear {:g} zfar {}", c.xmag, c.ymag, c.nearPlane, far);
    else
      projection = fmt::format("perspective yfov {:.4g} deg aspect {} znear {:g} zfar {}", glm::degrees(c.fovY),
                               c.aspectRatio > 0.0 ? fmt::format("{:.4g}", c.aspectRatio) : std::string("viewport"),
                               c.nearPlane, far);
    const glm::dvec3 d = glm::normalize(c.target - c.position);
    out += fmt::format("{}  '{}'  {}  position {:.6g},{:.6g},{:.6g}  direction {:.4f},{:.4f},{:.4f}\n", i,
                       printable(scene.cameras[i].name), projection, c.position.x, c.position.y, c.position.z, d.x,
                       d.y, d.z);
  }
  return out;
}

Result<Camera> makeCamera(const CameraOptions& o, const Scene& scene) {
  Camera c = scene.defaultCamera;
  if (!o.camera.empty()) {
    std::string listed = describeCameras(scene);  // one line per camera; "; " between them in a message
    listed.pop_back();
    for (size_t at = listed.find('\n'); at != std::string::npos; at = listed.find('\n', at))
      listed.replace(at, 1, "; ");
    const std::string& v = o.camera;
    size_t index = 0;
    bool known = v == "gltf";
    if (!known && v.rfind("gltf:", 0) == 0 && v.size() > 5 && v.size() <= 14 &&
        std::all_of(v.begin() + 5, v.end(), [](char ch) { return ch >= '0' && ch <= '9'; })) {
      index = std::stoull(v.substr(5));
      known = true;
    }
    if (!known)
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("--camera '{}': expected gltf, gltf:N or list; the scene's cameras: {}",
                                   printable(v), listed));
    if (index >= scene.cameras.size())
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("--camera {}: the scene has {} camera(s){}", printable(v), scene.cameras.size(),
                                   scene.cameras.empty() ? " (only a glTF file's camera nodes give cameras)"
                                                         : ": " + listed));
    c = scene.cameras[index].camera;
  }
  if (!o.position.empty()) c.position = {o.position[0], o.position[1], o.position[2]};
  if (!o.target.empty()) c.target = {o.target[0], o.target[1], o.target[2]};
  if (o.fovDegrees != 0.0) {
    if (!(o.fovDegrees > 0.0 && o.fovDegrees < 179.0))
      return makeError(ErrorCode::InvalidArgument, fmt::format("--fov {}: must be in (0, 179) degrees", o.fovDegrees));
    c.fovY = glm::radians(o.fovDegrees);
  }
  if (o.nearPlane < 0.0 || !std::isfinite(o.nearPlane))
    return makeError(ErrorCode::InvalidArgument, "--near must be a positive distance");
  if (o.nearPlane > 0.0) c.nearPlane = o.nearPlane;
  if (Status s = validateCamera(c); !s) return makeError(ErrorCode::InvalidArgument, s.error().message);
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
