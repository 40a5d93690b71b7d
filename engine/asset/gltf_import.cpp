// glTF 2.0 -> MeshSource / ImportedScene importer. The contract (what is supported, which errors) is in
// gltf_import.h.
//
// Pipeline:
//   1. loadModel() (gltf_container.cpp): read the file ourselves (regular files only, never blocking;
//      FileNotFound / IoError), check and re-pack the GLB container, check asset.version, resolve every
//      external uri by the URI rule (uri_resolver.h), neutralise EXT_meshopt_compression fallback buffers
//      (tinygltf 2.7 cannot load a buffer without data), then hand the bytes to tinygltf for JSON parsing and
//      loading the data-URI buffers and the approved external ones. The file, its buffers and everything
//      decoded below are charged to the memory budget (GltfImportOptions::maxMemoryBytes) before allocation.
//   2. Importer::run(): walk the scene graph with double-precision transforms; the first time a mesh is met,
//      decode its primitives into local-space arrays (cached, so a mesh instanced by 1000 nodes is decoded
//      once); then transform, morph and append each primitive instance to the output MeshSource.
//   2'. Importer::runScene() (importGltfScene): the same walk (walkScene), but each (mesh, material,
//      mirrored, weights) group is emitted once in object space and every node becomes instances with world
//      transforms. Materials and the images they use come from gltf_materials.cpp.
//
// This file holds the node graph checks, the scene walk and the entry points; the Importer's other methods are
// in gltf_accessors.cpp (buffer views, accessors), gltf_primitives.cpp (primitive decoding and emission),
// gltf_scene_mesh.cpp (scene meshes and instances), gltf_instancing.cpp (EXT_mesh_gpu_instancing) and
// gltf_lights.cpp (KHR_lights_punctual); gltf_detail.h declares the class.
//
// Safety rule: tinygltf only parses; it does not validate ranges. Every index, offset, count and stride that
// comes from the file is checked here with overflow-safe arithmetic before any byte is touched, and every
// problem becomes an Error (never an assert, exception or out-of-bounds read).

#include "visbuf/asset/gltf_import.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_animation.h"
#include "visbuf/asset/gltf_detail.h"

namespace visbuf {
namespace gltf_detail {

bool requiredExtensionSupported(const std::string& ext) {
  static constexpr const char* kIgnorablePrefixes[] = {"KHR_materials_", "KHR_texture_",  "EXT_texture_",
                                                       "KHR_lights_",    "MSFT_texture_", "KHR_xmp"};
  if (ext == kMeshoptExt || ext == kQuantizationExt || ext == kInstancingExt || ext == kDracoExt) return true;
  return std::any_of(std::begin(kIgnorablePrefixes), std::end(kIgnorablePrefixes),
                     [&](const char* prefix) { return ext.rfind(prefix, 0) == 0; });
}

// Required extensions that change how geometry must be read are either handled or refused (loadModel refuses
// the unsupported ones before the parser runs: requiredExtensionSupported); here the handled ones set the flags.
Status Importer::checkRequiredExtensions() {
  for (const std::string& ext : model_.extensionsRequired) {
    if (ext == kMeshoptExt) meshoptRequired_ = true;
    if (ext == kInstancingExt) instancingRequired_ = true;
    if (!requiredExtensionSupported(ext))
      return makeError(ErrorCode::Unsupported, path_ + ": required extension '" + ext + "' is not supported");
  }
  return {};
}

// Depth-first walk of the default scene with an explicit stack (no recursion depth limit from the file),
// calling visit(nodeIndex, world) for every node in document order. glTF node graphs are disjoint trees, so a
// node met twice means a cycle or a shared child: refuse rather than loop or explode. `sceneLabel` receives a
// description of the roots for messages.
template <typename Visit>
Status Importer::walkScene(Visit&& visit, std::string* sceneLabel) {
  if (Status s = checkRequiredExtensions(); !s) return s;
  if (Status s = checkNodeGraph(); !s) return s;
  meshCache_.resize(model_.meshes.size());
  const size_t nodeCount = model_.nodes.size();

  // Root nodes: the chosen scene's, or every parentless node when the file has no scenes.
  std::vector<int> roots;
  if (!model_.scenes.empty()) {
    int scene = model_.defaultScene;
    if (scene < 0) scene = 0;
    if (static_cast<size_t>(scene) >= model_.scenes.size()) {
      return malformed(path_ + ": default scene " + str(scene) + " does not exist");
    }
    roots = model_.scenes[static_cast<size_t>(scene)].nodes;
    *sceneLabel = "scene " + str(scene);
  } else {
    std::vector<uint8_t> hasParent(nodeCount, 0);
    for (const tinygltf::Node& node : model_.nodes) {
      for (int child : node.children) {
        if (child >= 0 && static_cast<size_t>(child) < nodeCount) hasParent[static_cast<size_t>(child)] = 1;
      }
    }
    for (size_t i = 0; i < nodeCount; ++i) {
      if (!hasParent[i]) roots.push_back(static_cast<int>(i));
    }
    *sceneLabel = "root nodes (file has no scenes)";
  }

  std::vector<uint8_t> visited(nodeCount, 0);
  std::vector<std::pair<int, glm::dmat4>> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
  while (!stack.empty()) {
    auto [nodeIndex, parentWorld] = stack.back();
    stack.pop_back();
    if (nodeIndex < 0 || static_cast<size_t>(nodeIndex) >= nodeCount) {
      return malformed(path_ + ": node " + str(nodeIndex) + " does not exist (referenced by " + *sceneLabel +
                       " or a parent node)");
    }
    const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
    if (visited[static_cast<size_t>(nodeIndex)]) {
      return malformed(path_ + ": node " + str(nodeIndex) + named(node.name) +
                       " is reached twice (node graph has a cycle or a node with several parents)");
    }
    visited[static_cast<size_t>(nodeIndex)] = 1;
    auto local = localMatrix(nodeIndex);
    if (!local) return local.error();
    const glm::dmat4 world = parentWorld * *local;
    if (!isFinite(world))
      return malformed(path_ + ": node " + str(nodeIndex) + named(node.name) + ": non-finite transform");
    if (Status s = visit(nodeIndex, world); !s) return s;
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
  }
  return {};
}

// glTF nodes form disjoint trees: every node has at most one parent and no node is its own ancestor. Checked
// over ALL the file's nodes, whether or not the default scene reaches them (a child index that does not
// exist is reported by walkScene when reached).
Status Importer::checkNodeGraph() {
  const size_t n = model_.nodes.size();
  std::vector<int> parent(n, -1);
  for (size_t i = 0; i < n; ++i) {
    for (const int child : model_.nodes[i].children) {
      if (child < 0 || static_cast<size_t>(child) >= n) continue;
      const size_t c = static_cast<size_t>(child);
      if (c == i) {
        return malformed(path_ + ": node " + str(child) + named(model_.nodes[c].name) +
                         " is its own child (the node graph has a cycle)");
      }
      if (parent[c] >= 0) {
        return malformed(path_ + ": node " + str(child) + named(model_.nodes[c].name) + " has several parents (nodes " +
                         str(parent[c]) + " and " + str(uint64_t{i}) + ")");
      }
      parent[c] = static_cast<int>(i);
    }
  }
  // One parent each: a cycle is a loop of parent links. Walk up from every node; 1 = on this walk, 2 = known
  // to end at a root.
  std::vector<uint8_t> state(n, 0);
  std::vector<size_t> walk;
  for (size_t i = 0; i < n; ++i) {
    walk.clear();
    int v = static_cast<int>(i);
    while (v >= 0 && state[static_cast<size_t>(v)] == 0) {
      state[static_cast<size_t>(v)] = 1;
      walk.push_back(static_cast<size_t>(v));
      v = parent[static_cast<size_t>(v)];
    }
    if (v >= 0 && state[static_cast<size_t>(v)] == 1) {
      return malformed(path_ + ": node " + str(v) + named(model_.nodes[static_cast<size_t>(v)].name) +
                       " is its own ancestor (the node graph has a cycle)");
    }
    for (const size_t w : walk) state[w] = 2;
  }
  return {};
}

// An axis-aligned box (already transformed) must stay within kMaxImportCoordinate.
Status Importer::checkCoordinates(const glm::dvec3& lo, const glm::dvec3& hi, const std::string& where) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(lo[a]) <= kMaxImportCoordinate && std::abs(hi[a]) <= kMaxImportCoordinate)) {
      return malformed(where + ": world-space bounds (" + fmtCoord(lo.x) + ", " + fmtCoord(lo.y) + ", " +
                       fmtCoord(lo.z) + ") .. (" + fmtCoord(hi.x) + ", " + fmtCoord(hi.y) + ", " + fmtCoord(hi.z) +
                       ") reach too far from the origin (|coordinate| > " + fmtCoord(kMaxImportCoordinate) +
                       "): bounds would overflow");
    }
  }
  return {};
}

// Optional streams that some primitive had get their defaults for the vertices of the ones emitted after it.
void padOptionalStreams(MeshSource* m) {
  const size_t n = m->positions.size();
  if (!m->uvs.empty()) m->uvs.resize(n, glm::vec2(0.0f));
  if (!m->colors.empty()) m->colors.resize(n, 0xFFFFFFFFu);
  if (!m->uvs1.empty()) m->uvs1.resize(n, glm::vec2(0.0f));
  if (!m->tangents.empty()) m->tangents.resize(n, glm::vec4(0.0f));
}

Result<MeshSource> Importer::run() {
  MeshSource out;
  out.name = std::filesystem::path(path_).stem().string();
  std::string sceneLabel;
  Status walked = walkScene(
      [&](int nodeIndex, const glm::dmat4& world) -> Status {
        auto worlds = meshInstances(nodeIndex, world, false);
        if (!worlds) return worlds.error();
        for (const glm::dmat4& w : *worlds)
          if (Status s = emitNode(nodeIndex, w, &out); !s) return s;
        return {};
      },
      &sceneLabel);
  if (!walked) return walked.error();

  if (out.indices.empty()) {
    return malformed(path_ + ": no triangle geometry in " + sceneLabel + " (" +
                     str(uint64_t{primitivesSkipped}) + " primitive(s) skipped)");
  }
  padOptionalStreams(&out);
  return out;
}

Result<ImportedScene> Importer::runScene() {
  ImportedScene scene;
  scene.name = std::filesystem::path(path_).stem().string();
  const WarnFn warnFn = [this](const std::string& message) { warn(message); };
  if (Status s = importMaterials(model_, path_, warnFn, &scene.materials); !s) return s.error();
  if (Status s = collectImages(model_, path_, references_, &scene.images); !s) return s.error();
  const ReadFloats read = [this](int accessor, const std::string& where, std::vector<float>* out) {
    int n = 0;
    return readFloats(accessor, AttributeKind::Unchecked, where, out, &n);
  };
  if (Status s = importAnimationData(model_, path_, read, warnFn, &scene); !s) return s.error();
  for (const AnimationClip& clip : scene.animations)
    for (const AnimationChannel& c : clip.channels)
      (c.path == AnimationPath::Weights ? morphAnimatedNodes_ : movingNodes_).insert(static_cast<int>(c.node));
  // A node moves when a TRS channel targets it or any of its ancestors (the hierarchy has no cycles: checked).
  if (!movingNodes_.empty()) {
    for (size_t n = 0; n < scene.nodes.size(); ++n) {
      for (int32_t a = int32_t(n); a >= 0; a = scene.nodes[size_t(a)].parent) {
        if (movingNodes_.count(a)) {
          movingNodes_.insert(int(n));
          break;
        }
      }
    }
  }
  std::string sceneLabel;
  Status walked = walkScene(
      [&](int nodeIndex, const glm::dmat4& world) { return emitSceneNode(nodeIndex, world, &scene); },
      &sceneLabel);
  if (!walked) return walked.error();
  if (Status s = checkSkinnedInstances(scene, path_); !s) return s.error();
  if (scene.instances.empty()) {
    return malformed(path_ + ": no triangle geometry in " + sceneLabel + " (" +
                     str(uint64_t{primitivesSkipped}) + " primitive(s) skipped)");
  }
  return scene;
}

}  // namespace gltf_detail

using namespace gltf_detail;

namespace {
// Shared by both entry points: load, run one importer method, report, and keep every exception from
// tinygltf/nlohmann (allocation failure, pathological JSON) inside the engine boundary.
template <typename T>
Result<T> importWith(const std::string& path, const GltfImportOptions& options, GltfImportReport* report,
                     Result<T> (Importer::*run)()) {
  GltfImportReport localReport;
  GltfImportReport& rep = report ? *report : localReport;
  rep = GltfImportReport{};
  try {
    MemoryBudget budget(options.maxMemoryBytes);
    tinygltf::Model model;
    LoadedReferences references;
    if (Status s = loadModel(path, options, &budget, &model, &references, &rep.warnings); !s) return s.error();
    Importer importer(path, model, options, references, &budget, &rep.warnings);
    Result<T> result = (importer.*run)();
    rep.primitivesImported = importer.primitivesImported;
    rep.primitivesSkipped = importer.primitivesSkipped;
    return result;
  } catch (const std::bad_alloc&) {
    return makeError(ErrorCode::CapacityExceeded, path + ": out of memory while importing");
  } catch (const std::exception& e) {
    return malformed(path + ": " + e.what());
  }
}
}  // namespace

Result<MeshSource> importGltfMesh(const std::string& path, const GltfImportOptions& options,
                                  GltfImportReport* report) {
  return importWith<MeshSource>(path, options, report, &Importer::run);
}

Result<ImportedScene> importGltfScene(const std::string& path, const GltfImportOptions& options,
                                      GltfImportReport* report) {
  return importWith<ImportedScene>(path, options, report, &Importer::runScene);
}

}  // namespace visbuf
