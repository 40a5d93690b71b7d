// Scene selection shared by the subcommands: built-in layouts, a glTF file or a baked pack.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/load_scene.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

struct SceneOptions {
  std::string scene = "field";  // field | city | foliage | foliage-opaque | terrain | .gltf/.glb | a pack (.vbp)
  uint32_t objects = 0;         // 0: the layout's default (a file: 1 copy; LoadOptions::instances)
  uint64_t seed = 1;
  uint32_t terrainSize = 0;     // terrain: vertices per side (--terrain-size); 0 = TerrainParams' default
  std::string mesh;             // field: instanced mesh file (.gltf/.glb); empty = procedural knot
  uint32_t lights = 0;          // point lights scattered over the scene (scatterPointLights)
  bool noSun = false;           // switch the directional light off
  uint32_t materials = 0;       // generated layouts: replace the materials with N generated ones (applyGeneratedMaterials)
  std::string objectOrder = "spatial";  // spatial (orderObjectsSpatially) | as-built (--object-order)
  // A file's budgets and policy (--allow-uri-root, --max-image-pixels, --max-instances, --max-import-memory,
  // --ignore-required-extension, --strict-images); its instances, seed and order come from the fields above.
  LoadOptions load;
};

void addSceneOptions(CLI::App& app, SceneOptions& options);
// --max-instances and --max-import-memory (GltfImportOptions::maxInstances / maxMemoryBytes), for every command
// that imports a glTF (render, bake): the budgets docs/security.md states, raised on purpose.
void addImportBudgetOptions(CLI::App& app, uint64_t& maxInstances, uint64_t& maxImportMemory);
// --ignore-required-extension (GltfImportOptions::ignoreRequiredExtensions) and --strict-images
// (TextureBakeOptions::dropUndecodableImages off), for the same commands: what a file that asks for more than
// visbuf reads may do (gltf_extensions.h).
void addExtensionPolicyOptions(CLI::App& app, std::vector<std::string>& ignoreRequired, bool& strictImages);
// Notes the files the options name (--scene when it is a file, not a layout; --mesh) as inputs of this command
// (core/file_read.h), so that checkOutputs refuses an output aimed at one before any work.
void noteSceneInputs(const SceneOptions& options);
// True when --scene names a built-in layout rather than a file.
bool isLayoutName(const std::string& scene);
// The scene the options name: a generated layout, or a file through visbuf::loadScene (its warnings printed to
// stderr), then --materials, --lights and --no-sun.
Result<Scene> loadScene(const SceneOptions& options);

struct CameraOptions {
  std::string camera;            // --camera: empty (the scene's default camera), "gltf" / "gltf:N", "list"
  std::vector<double> position;  // x,y,z; empty = the chosen camera's
  std::vector<double> target;
  double fovDegrees = 0.0;       // 0 = the chosen camera's (perspective only)
  double nearPlane = 0.0;        // 0 = the chosen camera's
};

void addCameraOptions(CLI::App& app, CameraOptions& options);
// The camera a command starts from: the scene's default camera or, with --camera gltf[:N], the file's camera N
// (Scene::cameras; 0 without N), then --camera-pos / --camera-target / --fov / --near over it. InvalidArgument for
// a camera index the scene does not have or an unknown --camera value (its message lists the scene's cameras).
Result<Camera> makeCamera(const CameraOptions& options, const Scene& scene);
// True when --camera asks for the list (`--camera` alone or `--camera list`): the command prints
// describeCameras() to stdout and exits 0 instead of rendering.
bool camerasListRequested(const CameraOptions& options);
// One line per camera of the scene: index, name, type and parameters (degrees for angles), pose.
std::string describeCameras(const Scene& scene);

// Parses "WxH".
Result<std::pair<uint32_t, uint32_t>> parseSize(const std::string& text);

}  // namespace visbuf::tools
