// One call from a file to a scene the Renderer takes: loadScene() reads a glTF file (.gltf / .glb) or a baked
// visbuf pack (.vbp, `visbuf bake`) and returns it assembled the way `visbuf render --scene FILE` shows it:
// meshes with their LOD chains, materials with their baked textures, KHR_lights_punctual lights, skins, morph
// targets and node animation, the file's cameras, optional copies of the whole scene (instancing) and the
// objects in spatial order. A glTF goes through the same steps as `visbuf bake` (importGltfScene,
// buildImportedScene, bakeTextures with the bake's default texture options), so rendering a glTF directly and
// rendering the pack baked from it give the same image.
//
//   visbuf::LoadOptions options;
//   options.instances = 100;                      // 100 copies of the file's scene, each animated at its phase
//   visbuf::Result<visbuf::LoadedScene> loaded = visbuf::loadScene("Fox.glb", options);
//   if (!loaded) return report(loaded.error());   // ErrorCode + a message naming the file and the problem
//   for (const std::string& w : loaded->warnings) log(w);
//   auto renderer = visbuf::Renderer::create(device, loaded->scene, config);
//
// Files are untrusted input (docs/security.md): every budget below is checked before the memory it bounds is
// allocated, and a file that exceeds one fails with CapacityExceeded naming the budget. Nothing is printed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

enum class SceneFileKind { Gltf, Pack };

// How the objects are numbered once the scene is assembled.
enum class ObjectOrder {
  Spatial,  // along a Morton curve of their positions (orderObjectsSpatially): the same image, and the GPU-driven
            // passes read neighbouring objects together
  AsBuilt,  // in the order the file lists them (glTF: node order; copies one after another)
};

struct LoadOptions {
  // Copies of the file's scene (>= 1). More than one: each copy scaled to a unit bounding radius, standing on a
  // jittered grid with a random heading, its animated objects (skinned, morphed, node-animated) playing their
  // clip at the copy's own phase; meshes, materials and textures shared; the file's punctual lights placed with
  // every copy (makeAnimatedField, generate.h). Its cameras are dropped (they framed the file's one copy).
  uint32_t instances = 1;
  uint64_t seed = 1;  // the copies' jitter, headings and phases
  // Objects the copies may make (file objects x instances), refused with CapacityExceeded before any copy is
  // made; at most 2^32 - 1 (object indices are 32-bit). A host sets what its device addresses.
  uint64_t maxObjects = UINT32_MAX;
  ObjectOrder objectOrder = ObjectOrder::Spatial;

  // --- glTF import budgets and policy (GltfImportOptions; docs/security.md)
  // Folders besides the file's own that its external buffer / image uris may resolve into (each must exist).
  std::vector<std::string> allowedUriRoots;
  // Mesh instances one import may create (nodes, EXT_mesh_gpu_instancing), before any is built.
  uint64_t maxInstances = kDefaultMaxInstances;
  // Bytes the import may hold (file, JSON, buffers, decoded accessors, output), checked before each allocation;
  // for a pack, what its zstd sections may decode to (PackReadOptions::maxDecodedBytes); for copies, their
  // object, skinned, rigid and light records (checked before any copy is made).
  uint64_t maxImportMemory = kDefaultImportMemoryBytes;
  // Required extensions imported anyway ("*": any), each with a warning (gltf_extensions.h).
  std::vector<std::string> ignoreRequiredExtensions;

  // --- glTF textures (TextureBakeOptions; the rest of them at their defaults, as `visbuf bake` bakes)
  uint32_t maxTextureSize = TextureBakeOptions{}.maxTextureSize;  // power of two in [1, 16384]
  // Pixels an image's header may declare, refused before it is decoded.
  uint64_t maxImagePixels = kDefaultMaxImagePixels;
  // false (the default): an image that cannot be decoded drops its texture with a warning; true: it fails the
  // load.
  bool strictImages = false;
};

struct LoadedScene {
  Scene scene;
  SceneFileKind kind = SceneFileKind::Gltf;
  // Non-fatal problems, one line each, in the order found (import: skipped primitives, ignored extensions, ...;
  // textures: dropped images). The caller decides whether and where to show them.
  std::vector<std::string> warnings;
};

// The import budgets and policy of `options` as importGltfScene / importGltfMesh take them (the rest at their
// defaults).
GltfImportOptions gltfImportOptions(const LoadOptions& options);

// Pack when the file starts with the pack magic (isPackFile) or is named *.vbp (so that a damaged pack gets
// the pack reader's message rather than the glTF parser's); glTF otherwise (the parser tells .gltf JSON from .glb
// by content).
SceneFileKind sceneFileKind(const std::filesystem::path& path);

// Loads `path` as described above. Errors (each names the file, and the mesh / image / node / budget at fault):
// InvalidArgument (options out of range: instances 0, maxTextureSize not a power of two in [1, 16384],
// maxImagePixels 0, a missing allowed root), FileNotFound, IoError, MalformedInput (a file that is not valid
// glTF or pack, or whose contents are inconsistent), Unsupported (a required extension visbuf does not read, a
// build without an image decoder for a textured glTF), CapacityExceeded (a budget above, maxObjects
// included).
Result<LoadedScene> loadScene(const std::filesystem::path& path, const LoadOptions& options = {});

// The steps after the file is read, shared by both kinds and usable on any scene a host built itself: copies
// (options.instances > 1) and the object order. InvalidArgument for 0 instances or a scene without objects to
// copy; CapacityExceeded when the copies would pass options.maxObjects or their records options.maxImportMemory.
Result<Scene> finishScene(Scene scene, const LoadOptions& options);

}  // namespace visbuf
