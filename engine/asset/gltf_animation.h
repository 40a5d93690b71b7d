// Internal to engine/asset: the skinning and animation half of the glTF importer (gltf_animation.cpp).
// It reads accessors through the importer's validated reader (a callback), so every range check stays in
// one place (gltf_import.cpp). Not installed as public API.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/type_precision.hpp>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

// Reads every element of an accessor as floats (normalized integers decoded per the glTF spec), all range
// checks done; the caller has checked type and component type against the model.
using ReadFloats = std::function<Status(int accessor, const std::string& where, std::vector<float>* out)>;
using Warn = std::function<void(const std::string& message)>;

// A primitive's skin streams: influences 1-4 (JOINTS_0 / WEIGHTS_0) and, for 8-influence vertices, 5-8
// (JOINTS_1 / WEIGHTS_1; empty otherwise).
struct SkinStreams {
  std::vector<glm::u16vec4> joints;
  std::vector<glm::vec4> weights;
  std::vector<glm::u16vec4> joints1;
  std::vector<glm::vec4> weights1;
};

// Turns decoded JOINTS_n / WEIGHTS_n values (`influences` = 4 or 8 floats per vertex each: JOINTS_0's 4, then
// JOINTS_1's) into the MeshSource streams: weights renormalised to sum 1 over all the vertex's influences; a
// vertex whose weights sum to 0 gets weight 1 on its first joint slot (one warning per primitive); negative or
// non-finite weights are MalformedInput; slots with weight 0 get joint 0.
Status convertSkinAttributes(const std::vector<float>& joints, const std::vector<float>& weights, int influences,
                             const std::string& where, const Warn& warn, SkinStreams* out);

// Fills scene->nodes (every glTF node, in file order), scene->skins and scene->animations. Does nothing when
// the file has neither skins nor animations. Errors name the node / skin / animation / accessor.
Status importAnimationData(const tinygltf::Model& model, const std::string& path, const ReadFloats& read,
                           const Warn& warn, ImportedScene* scene);

// After the scene walk: every skinned instance's mesh has skin streams whose joint indices are below its
// skin's joint count (MalformedInput naming node, mesh and skin otherwise).
Status checkSkinnedInstances(const ImportedScene& scene, const std::string& path);

}  // namespace visbuf::gltf_detail
