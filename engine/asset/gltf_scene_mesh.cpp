// glTF importer (gltf_import.h), scene import: each node's mesh instances grouped into ImportedMesh entries
// (one per glTF mesh, material, mirroring, morph weights), with skin and morph-target streams, and the
// one-joint skins of unskinned animated nodes.

#include <algorithm>
#include <cmath>
#include <cstring>
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
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

namespace {

// Appends a primitive's skin streams to `out` (whose vertices of this primitive start at `base`). Vertices
// without skin data, before or after skinned ones, get joint 0 with weight 1 (only meshes drawn by
// unskinned nodes can mix: checkSkinnedNode refuses it for skinned ones).
void appendSkinStreams(const DecodedPrimitive& prim, size_t base, MeshSource* out) {
  if (prim.joints.empty() && out->joints.empty()) return;
  out->joints.resize(base, glm::u16vec4(0));
  out->weights.resize(base, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  out->joints.insert(out->joints.end(), prim.joints.begin(), prim.joints.end());
  out->weights.insert(out->weights.end(), prim.weights.begin(), prim.weights.end());
  const size_t end = std::max(out->positions.size(), out->joints.size());
  out->joints.resize(end, glm::u16vec4(0));
  out->weights.resize(end, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  // Influences 5-8: zero weight (joint 0) for the vertices of primitives with 4 or none, once any has 8.
  if (prim.joints1.empty() && out->joints1.empty()) return;
  out->joints1.resize(base, glm::u16vec4(0));
  out->weights1.resize(base, glm::vec4(0.0f));
  out->joints1.insert(out->joints1.end(), prim.joints1.begin(), prim.joints1.end());
  out->weights1.insert(out->weights1.end(), prim.weights1.begin(), prim.weights1.end());
  out->joints1.resize(end, glm::u16vec4(0));
  out->weights1.resize(end, glm::vec4(0.0f));
}

// Appends a primitive's morph deltas (its vertices start at `base` in `out`) for the mesh's `targetCount`
// targets: a stream that some primitive has is zero for the vertices of those that lack it.
void appendMorphStreams(const DecodedPrimitive& prim, size_t base, size_t targetCount, MeshSource* out) {
  out->morphTargets.resize(targetCount);
  const size_t end = out->positions.size();
  for (size_t t = 0; t < targetCount; ++t) {
    MeshSource::MorphTarget& dst = out->morphTargets[t];
    auto put = [&](std::vector<glm::vec3>& stream, const std::vector<SharedVec3>& deltas) {
      const bool has = t < deltas.size() && deltas[t];
      if (!has && stream.empty()) return;
      stream.resize(base, glm::vec3(0.0f));
      if (has) stream.insert(stream.end(), deltas[t]->begin(), deltas[t]->end());
      stream.resize(end, glm::vec3(0.0f));
    };
    put(dst.positions, prim.positionDeltas);
    put(dst.normals, prim.normalDeltas);
    put(dst.tangents, prim.tangentDeltas);
  }
}

// The bytes appendMorphStreams() adds for the primitives of `mesh` that use `gltfMaterial`: every vertex of
// the group gets each of `targetCount` targets' streams that any of its primitives has (zeros where one lacks it).
uint64_t morphStreamBytes(const std::vector<DecodedPrimitive>& prims, const tinygltf::Mesh& mesh, int gltfMaterial,
                          size_t targetCount) {
  uint64_t vertices = 0;
  bool has[3] = {false, false, false};
  for (size_t p = 0; p < prims.size(); ++p) {
    if (mesh.primitives[p].material != gltfMaterial || prims[p].skipped) continue;
    vertices += prims[p].positions.size();
    int k = 0;
    for (const auto* deltas : {&prims[p].positionDeltas, &prims[p].normalDeltas, &prims[p].tangentDeltas}) {
      for (const SharedVec3& d : *deltas) has[k] = has[k] || d != nullptr;
      ++k;
    }
  }
  const uint64_t streams = uint64_t{has[0]} + uint64_t{has[1]} + uint64_t{has[2]};
  uint64_t bytes = 0;
  if (!checkedMul(vertices, streams * sizeof(glm::vec3), &bytes) || !checkedMul(bytes, targetCount, &bytes))
    return UINT64_MAX;
  return bytes;
}

}  // namespace

// A skinned node's skin exists and every primitive it draws has JOINTS_0 / WEIGHTS_0 (glTF requires both).
Status Importer::checkSkinnedNode(int nodeIndex, const std::vector<DecodedPrimitive>& prims,
                                  const std::string& where) {
  const int skin = model_.nodes[static_cast<size_t>(nodeIndex)].skin;
  if (static_cast<size_t>(skin) >= model_.skins.size())
    return malformed(where + ": skin " + str(skin) + " does not exist");
  for (size_t p = 0; p < prims.size(); ++p) {
    if (!prims[p].skipped && prims[p].joints.empty())
      return malformed(where + ": skinned, but primitive " + str(uint64_t{p}) + " has no JOINTS_0 / WEIGHTS_0");
  }
  return {};
}

// A node's light and camera (once, at the node) and its mesh: once, or once per EXT_mesh_gpu_instancing instance.
Status Importer::emitSceneNode(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  if (Status s = emitNodeLight(nodeIndex, world, scene); !s) return s;
  if (Status s = emitNodeCamera(nodeIndex, world, scene); !s) return s;
  auto worlds = meshInstances(nodeIndex, world, true);
  if (!worlds) return worlds.error();
  for (const glm::dmat4& w : *worlds)
    if (Status s = emitSceneMesh(nodeIndex, w, scene); !s) return s;
  return {};
}

// Adds one instance of node `nodeIndex`'s mesh at `world` to `scene`: one per material group of its mesh.
Status Importer::emitSceneMesh(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  auto resolved = nodeMesh(nodeIndex);
  if (!resolved) return resolved.error();
  if (!resolved->mesh) return {};
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  const std::string& nodeWhere = resolved->where;
  const tinygltf::Mesh& mesh = *resolved->mesh;
  const std::vector<DecodedPrimitive>* const* prims = &resolved->prims;
  const std::vector<double>& weights = *resolved->weights;

  const double det = glm::determinant(glm::dmat3(world));
  // Not just det == 0: validateScene() rejects objects with |det| < 1e-30 as degenerate, so a node scaled by
  // e.g. 1e-11 on every axis (det 1e-33) must be skipped here too, or a scene that imports would fail to
  // validate after buildImportedScene() (found by GltfFuzz; regression: GltfFuzz.NearlySingularNodeIsSkipped).
  if (!(std::abs(det) >= 1e-30)) {
    warn(nodeWhere + ": zero-scale (singular) transform; instance skipped");
    return {};
  }
  const bool mirrored = det < 0.0;
  if (node.skin >= 0) {
    if (Status s = checkSkinnedNode(nodeIndex, **prims, nodeWhere); !s) return s;
  }
  // Morph targets stay deltas (not baked) when a clip animates this node's weights.
  size_t morphTargets = 0;
  for (const DecodedPrimitive& prim : **prims)
    if (!prim.skipped) morphTargets = std::max(morphTargets, prim.positionDeltas.size());
  const bool morphed = morphTargets > 0 && morphAnimatedNodes_.count(nodeIndex) > 0;
  // An unskinned node whose weights a clip animates is skinned with a one-joint skin whose joint is the node
  // itself (identity inverse bind): the joint's global matrix is exactly the node transform glTF applies to an
  // unskinned mesh, so its motion plays through the skinning pass too. An unskinned node without animated
  // weights whose global transform a clip animates (CesiumMilkTruck's wheels) stays a plain mesh: its instances
  // are rigid (ImportedInstance::rigid), placed by the node's animated global matrix.
  const bool oneJoint = node.skin < 0 && morphed;
  const bool rigid = node.skin < 0 && !morphed && movingNodes_.count(nodeIndex) > 0;
  static const std::vector<double> kUnmorphed;

  // Material groups in order of first appearance among the primitives.
  std::vector<int> groups;
  for (const tinygltf::Primitive& p : mesh.primitives) {
    if (p.material >= 0 && static_cast<size_t>(p.material) >= model_.materials.size()) {
      return malformed(nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + ": material " +
                       str(p.material) + " does not exist");
    }
    if (std::find(groups.begin(), groups.end(), p.material) == groups.end()) groups.push_back(p.material);
  }

  for (const int gltfMaterial : groups) {
    SceneMeshKey key{node.mesh, gltfMaterial, mirrored, weights, morphed, oneJoint};
    auto found = sceneMeshes_.find(key);
    uint32_t meshIndex = 0;
    uint32_t groupPrimitives = 0;
    for (size_t p = 0; p < (*prims)->size(); ++p) {
      if (mesh.primitives[p].material == gltfMaterial && !(**prims)[p].skipped) ++groupPrimitives;
    }
    if (found == sceneMeshes_.end()) {
      ImportedMesh im;
      im.gltfMesh = node.mesh;
      im.mirrored = mirrored;
      if (gltfMaterial >= 0) {
        im.material = static_cast<uint32_t>(gltfMaterial);
      } else {
        if (!defaultMaterial_) {
          defaultMaterial_ = static_cast<uint32_t>(scene->materials.size());
          Material m;
          m.name = "default";
          scene->materials.push_back(m);
        }
        im.material = *defaultMaterial_;
      }
      im.source.name = mesh.name.empty() ? "mesh" + str(node.mesh) : mesh.name;
      if (groups.size() > 1) im.source.name += "/" + scene->materials[im.material].name;
      if (mirrored) im.source.name += " (mirrored)";
      // Kept morph targets: the whole group's target streams, charged before the first is appended.
      if (morphed) {
        const uint64_t bytes = morphStreamBytes(**prims, mesh, gltfMaterial, morphTargets);
        if (Status s = budget_->charge(bytes, nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + ": " +
                                                  str(uint64_t{morphTargets}) + " animated morph targets");
            !s)
          return s;
      }
      // Object space: identity transform. Normals are generated (when missing) from the file's winding.
      for (size_t p = 0; p < (*prims)->size(); ++p) {
        const DecodedPrimitive& prim = (**prims)[p];
        if (mesh.primitives[p].material != gltfMaterial || prim.skipped) continue;
        const std::string where =
            nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + " primitive " + str(uint64_t{p});
        const size_t base = im.source.positions.size();
        if (Status s = emitPrimitive(prim, glm::dmat4(1.0), morphed ? kUnmorphed : weights, where, &im.source); !s)
          return s;
        appendSkinStreams(prim, base, &im.source);
        if (morphed) appendMorphStreams(prim, base, morphTargets, &im.source);
      }
      appendSkinStreams(DecodedPrimitive{}, im.source.positions.size(), &im.source);  // pad to the end
      if (morphed) {
        if (weights.size() != morphTargets)
          warn(nodeWhere + ": " + str(uint64_t{weights.size()}) + " morph weights for " + str(uint64_t{morphTargets}) +
               " targets; missing ones are 0");
        im.source.morphWeights.assign(morphTargets, 0.0f);
        for (size_t t = 0; t < morphTargets && t < weights.size(); ++t)
          im.source.morphWeights[t] = static_cast<float>(weights[t]);
      }
      if (oneJoint) {  // every vertex follows joint 0 of the node's one-joint skin
        im.source.joints.assign(im.source.positions.size(), glm::u16vec4(0));
        im.source.weights.assign(im.source.positions.size(), glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
        im.source.joints1.clear();
        im.source.weights1.clear();
      }
      padOptionalStreams(&im.source);
      if (mirrored) {
        for (size_t i = 0; i + 2 < im.source.indices.size(); i += 3)
          std::swap(im.source.indices[i + 1], im.source.indices[i + 2]);
        // The instance transform mirrors: see transformTangent. Baked here so shaders need no det sign.
        for (glm::vec4& t : im.source.tangents) t.w = t.w == 0.0f ? 0.0f : -t.w;
      }
      if (im.source.indices.empty()) {
        meshIndex = std::numeric_limits<uint32_t>::max();  // every primitive of the group was skipped
      } else {
        meshIndex = static_cast<uint32_t>(scene->meshes.size());
        scene->meshes.push_back(std::move(im));
      }
      found = sceneMeshes_.emplace(std::move(key), meshIndex).first;
    }
    meshIndex = found->second;
    if (meshIndex != std::numeric_limits<uint32_t>::max()) {
      // The instance's world-space box: its mesh's object-space box (cached per mesh) through `world`.
      if (meshBoxes_.size() <= meshIndex) meshBoxes_.resize(meshIndex + 1);
      auto& box = meshBoxes_[meshIndex];
      if (!box) {
        glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        for (const glm::vec3& p : scene->meshes[meshIndex].source.positions) {
          lo = glm::min(lo, glm::dvec3(p));
          hi = glm::max(hi, glm::dvec3(p));
        }
        box = std::pair{lo, hi};
      }
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
      for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 c((corner & 1) ? box->second.x : box->first.x, (corner & 2) ? box->second.y : box->first.y,
                           (corner & 4) ? box->second.z : box->first.z);
        const glm::dvec3 w(world * glm::dvec4(c, 1.0));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
      if (Status s = checkCoordinates(lo, hi, nodeWhere); !s) return s;
    }
    // Counted per primitive instance, like importGltfMesh.
    uint32_t groupSkipped = 0;
    for (size_t p = 0; p < (*prims)->size(); ++p) {
      if (mesh.primitives[p].material == gltfMaterial && (**prims)[p].skipped) ++groupSkipped;
    }
    primitivesSkipped += groupSkipped;
    if (meshIndex == std::numeric_limits<uint32_t>::max()) continue;
    primitivesImported += groupPrimitives;
    ImportedInstance inst;
    inst.mesh = meshIndex;
    inst.material = scene->meshes[meshIndex].material;
    inst.transform = world;
    inst.node = nodeIndex;
    inst.skin = node.skin >= 0 ? node.skin : -1;
    inst.morphed = morphed;
    inst.rigid = rigid;
    if (oneJoint) {  // glTF applies the node's world matrix: a joint at the node does the same
      auto [it, added] = nodeSkins_.emplace(nodeIndex, int32_t(scene->skins.size()));
      if (added) {
        Skin skin;
        skin.name = (morphed ? "morph " : "node ") + (node.name.empty() ? "node " + str(nodeIndex) : node.name);
        skin.joints = {static_cast<uint32_t>(nodeIndex)};
        skin.inverseBindMatrices = {glm::dmat4(1.0)};
        scene->skins.push_back(std::move(skin));
      }
      inst.skin = it->second;
    }
    if (Status s = countInstances(1, nodeWhere); !s) return s;
    scene->instances.push_back(inst);
  }
  return {};
}

}  // namespace visbuf::gltf_detail
