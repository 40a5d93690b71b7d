// loadScene (load_scene.h): a glTF or a pack to a finished Scene.
#include "visbuf/asset/load_scene.h"

#include <algorithm>

#include <fmt/format.h>

#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/generate.h"

namespace visbuf {

namespace {

Status checkInstances(const LoadOptions& o) {
  if (o.instances == 0) return makeError(ErrorCode::InvalidArgument, "load options: instances must be at least 1");
  return {};
}

Status checkOptions(const LoadOptions& o) {
  if (Status s = checkInstances(o); !s) return s;
  if (o.maxTextureSize == 0 || o.maxTextureSize > kMaxBakedTextureSize || (o.maxTextureSize & (o.maxTextureSize - 1)))
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("load options: maxTextureSize {} is not a power of two in 1..{}", o.maxTextureSize,
                                 kMaxBakedTextureSize));
  if (o.maxImagePixels == 0) return makeError(ErrorCode::InvalidArgument, "load options: maxImagePixels is 0");
  return {};
}

// The glTF path: what `visbuf bake` does before it writes the pack (default mesh build and texture options
// besides the budgets), so that the scene equals the pack's.
Result<Scene> loadGltf(const std::string& path, const LoadOptions& o, std::vector<std::string>& warnings) {
  GltfImportReport report;
  Result<ImportedScene> imported = importGltfScene(path, gltfImportOptions(o), &report);
  warnings.insert(warnings.end(), report.warnings.begin(), report.warnings.end());
  if (!imported) return imported.error();
  Result<Scene> scene = buildImportedScene(*imported);
  if (!scene) return scene.error();
  TextureBakeOptions to;
  to.maxTextureSize = o.maxTextureSize;
  to.maxImagePixels = o.maxImagePixels;
  to.dropUndecodableImages = !o.strictImages;
  TextureBakeReport textureReport;
  Status t = bakeTextures(*imported, to, &*scene, &textureReport);
  warnings.insert(warnings.end(), textureReport.warnings.begin(), textureReport.warnings.end());
  if (!t) return t.error();
  scene->name = path;
  return scene;
}

}  // namespace

GltfImportOptions gltfImportOptions(const LoadOptions& o) {
  GltfImportOptions io;
  io.allowedUriRoots = o.allowedUriRoots;
  io.maxInstances = o.maxInstances;
  io.maxMemoryBytes = o.maxImportMemory;
  io.ignoreRequiredExtensions = o.ignoreRequiredExtensions;
  return io;
}

SceneFileKind sceneFileKind(const std::filesystem::path& path) {
  return isPackFile(path.string()) || path.extension() == ".vbp" ? SceneFileKind::Pack : SceneFileKind::Gltf;
}

Result<Scene> finishScene(Scene scene, const LoadOptions& o) {
  if (Status s = checkInstances(o); !s) return s.error();
  if (o.instances > 1) {
    // Object indices are 32-bit everywhere downstream (Object references, IDs, draw commands).
    const uint64_t limit = std::min<uint64_t>(o.maxObjects, UINT32_MAX);
    if (uint64_t(scene.objects.size()) * o.instances > limit)
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("{} copies of {} objects make {} objects, over the {} allowed", o.instances,
                                   scene.objects.size(), uint64_t(scene.objects.size()) * o.instances, limit));
    // What the copies' records take (the meshes, materials and textures are shared), within the import's memory
    // budget: a request for a billion copies fails here rather than in the allocator.
    const uint64_t perCopy = scene.objects.size() * sizeof(Object) +
                             scene.skinnedObjects.size() * sizeof(SkinnedObject) +
                             scene.rigidObjects.size() * sizeof(RigidObject) +
                             scene.pointLights.size() * sizeof(PointLight);
    if (perCopy * o.instances > o.maxImportMemory)
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("{} copies take {} bytes of object and light records ({} a copy), over the import "
                                   "memory budget of {} bytes (maxImportMemory)",
                                   o.instances, perCopy * o.instances, perCopy, o.maxImportMemory));
    AnimatedFieldParams p;
    p.instances = o.instances;
    p.seed = o.seed;
    Result<Scene> copies = makeAnimatedField(scene, p);
    if (!copies) return copies.error();
    scene = std::move(copies.value());
  }
  if (o.objectOrder == ObjectOrder::Spatial) orderObjectsSpatially(scene);
  return scene;
}

Result<LoadedScene> loadScene(const std::filesystem::path& path, const LoadOptions& options) {
  if (Status s = checkOptions(options); !s) return s.error();
  LoadedScene loaded;
  loaded.kind = sceneFileKind(path);
  Result<Scene> scene = loaded.kind == SceneFileKind::Pack
                            ? readPack(path.string(), PackReadOptions{options.maxImportMemory})
                            : loadGltf(path.string(), options, loaded.warnings);
  if (!scene) return scene.error();
  Result<Scene> finished = finishScene(std::move(scene.value()), options);
  if (!finished) return makeError(finished.error().code, path.string() + ": " + finished.error().message);
  loaded.scene = std::move(finished.value());
  return loaded;
}

}  // namespace visbuf
