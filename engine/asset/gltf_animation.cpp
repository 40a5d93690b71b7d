// The skinning and animation half of the glTF importer (gltf_animation.h): node hierarchy, skins, animation
// clips and per-vertex joints/weights. Accessor bytes are read through the importer's checked reader; this
// file checks accessor types, counts and values against what skins and animations need.
#include "visbuf/asset/gltf_animation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <utility>

namespace visbuf::gltf_detail {

namespace {

bool allFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

const char* typeName(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
  }
  return "other type";
}

// Checks an accessor's type; componentType must be FLOAT, or (allowNormalized) a normalized BYTE,
// UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT, as glTF allows for rotations and morph weights.
Status checkShape(const tinygltf::Model& model, int index, int type, bool allowNormalized,
                  const std::string& where) {
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
    return malformed(where + ": accessor does not exist");
  const tinygltf::Accessor& a = model.accessors[static_cast<size_t>(index)];
  const int ct = a.componentType;
  const bool normalizedInt =
      a.normalized && (ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                       ct == TINYGLTF_COMPONENT_TYPE_SHORT || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  if (a.type == type && (ct == TINYGLTF_COMPONENT_TYPE_FLOAT || (allowNormalized && normalizedInt)))
    return {};
  return malformed(where + ": unsupported format (type " + typeName(a.type) + ", componentType " + str(ct) +
                   "); expected " + typeName(type) + " of FLOAT" +
                   (allowNormalized ? " or normalized integers" : ""));
}

// Reads one glTF node's local transform into `out` (TRS or matrix); rotations are normalised.
Status importNodeTransform(const tinygltf::Node& n, const std::string& where, const Warn& warn,
                           SceneNode* out) {
  if (!allFinite(n.matrix) || !allFinite(n.translation) || !allFinite(n.rotation) || !allFinite(n.scale))
    return malformed(where + ": non-finite transform");
  if (!n.matrix.empty()) {
    if (n.matrix.size() != 16) return malformed(where + ": matrix must have 16 elements");
    out->hasMatrix = true;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) out->matrix[c][r] = n.matrix[static_cast<size_t>(c * 4 + r)];
    return {};
  }
  if ((!n.translation.empty() && n.translation.size() != 3) ||
      (!n.rotation.empty() && n.rotation.size() != 4) || (!n.scale.empty() && n.scale.size() != 3))
    return malformed(where + ": translation / rotation / scale must have 3 / 4 / 3 elements");
  if (!n.translation.empty()) out->rest.translation = {n.translation[0], n.translation[1], n.translation[2]};
  if (!n.scale.empty()) out->rest.scale = {n.scale[0], n.scale[1], n.scale[2]};
  if (!n.rotation.empty()) {
    const glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
    const double len = glm::length(q);
    if (len > 0.0 && std::isfinite(len)) {
      out->rest.rotation = q / len;
    } else {
      warn(where + ": zero-length or out-of-range rotation quaternion treated as identity");
    }
  }
  return {};
}

Status importNodes(const tinygltf::Model& model, const std::string& path, const Warn& warn,
                   std::vector<SceneNode>* nodes) {
  nodes->assign(model.nodes.size(), SceneNode{});
  for (size_t i = 0; i < model.nodes.size(); ++i) {
    const tinygltf::Node& n = model.nodes[i];
    const std::string where = path + ": node " + str(uint64_t{i}) + named(n.name);
    (*nodes)[i].name = n.name;
    if (Status s = importNodeTransform(n, where, warn, &(*nodes)[i]); !s) return s;
    for (int child : n.children) {
      if (child < 0 || static_cast<size_t>(child) >= nodes->size())
        return malformed(where + ": child node " + str(child) + " does not exist");
      SceneNode& c = (*nodes)[static_cast<size_t>(child)];
      if (c.parent >= 0)
        return malformed(where + ": child node " + str(child) + " already has parent node " + str(c.parent));
      c.parent = static_cast<int32_t>(i);
    }
  }
  if (Status s = validateNodes(*nodes); !s) return malformed(path + ": " + s.error().message);
  return {};
}

// Inverse bind matrices: `count` >= joints, finite, affine (a last row within 1e-5 of 0 0 0 1 is snapped).
Status importInverseBinds(const tinygltf::Model& model, const tinygltf::Skin& gs, const std::string& where,
                          const ReadFloats& read, Skin* skin) {
  const size_t joints = skin->joints.size();
  skin->inverseBindMatrices.assign(joints, glm::dmat4(1.0));
  if (gs.inverseBindMatrices < 0) return {};
  const std::string aw = where + " accessor " + str(gs.inverseBindMatrices) + " (inverseBindMatrices)";
  if (Status s = checkShape(model, gs.inverseBindMatrices, TINYGLTF_TYPE_MAT4, false, aw); !s) return s;
  std::vector<float> m;
  if (Status s = read(gs.inverseBindMatrices, aw, &m); !s) return s;
  if (m.size() / 16 < joints)
    return malformed(aw + ": count " + str(uint64_t{m.size() / 16}) + " is less than the joint count " +
                     str(uint64_t{joints}));
  for (size_t j = 0; j < joints; ++j) {
    glm::dmat4& ibm = skin->inverseBindMatrices[j];
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) ibm[c][r] = m[16 * j + static_cast<size_t>(c * 4 + r)];
    if (!std::all_of(&m[16 * j], &m[16 * j] + 16, [](float x) { return std::isfinite(x); }))
      return malformed(aw + ": matrix " + str(uint64_t{j}) + " is not finite");
    const glm::dvec4 lastRow(ibm[0][3], ibm[1][3], ibm[2][3], ibm[3][3]);
    if (glm::length(lastRow - glm::dvec4(0, 0, 0, 1)) > 1e-5)
      return malformed(aw + ": matrix " + str(uint64_t{j}) + " is not affine (last row must be 0 0 0 1)");
    ibm[0][3] = ibm[1][3] = ibm[2][3] = 0.0;
    ibm[3][3] = 1.0;
  }
  return {};
}

Status importSkins(const tinygltf::Model& model, const std::string& path, const ReadFloats& read,
                   size_t nodeCount, std::vector<Skin>* skins) {
  for (size_t i = 0; i < model.skins.size(); ++i) {
    const tinygltf::Skin& gs = model.skins[i];
    const std::string where = path + ": skin " + str(uint64_t{i}) + named(gs.name);
    Skin skin;
    skin.name = gs.name;
    if (gs.joints.empty()) return malformed(where + ": no joints");
    for (size_t j = 0; j < gs.joints.size(); ++j) {
      if (gs.joints[j] < 0 || static_cast<size_t>(gs.joints[j]) >= nodeCount)
        return malformed(where + ": joint " + str(uint64_t{j}) + " is node " + str(gs.joints[j]) +
                         ", which does not exist");
      skin.joints.push_back(static_cast<uint32_t>(gs.joints[j]));
    }
    if (Status s = importInverseBinds(model, gs, where, read, &skin); !s) return s;
    skin.skeleton = gs.skeleton >= 0 ? gs.skeleton : -1;
    if (Status s = validateSkin(skin, nodeCount, where); !s) return s;
    skins->push_back(std::move(skin));
  }
  return {};
}

// --- animations

bool parsePath(const std::string& name, AnimationPath* path) {
  static const std::pair<const char*, AnimationPath> kPaths[] = {{"translation", AnimationPath::Translation},
                                                                 {"rotation", AnimationPath::Rotation},
                                                                 {"scale", AnimationPath::Scale},
                                                                 {"weights", AnimationPath::Weights}};
  for (const auto& [text, value] : kPaths)
    if (name == text) *path = value;
  return std::any_of(std::begin(kPaths), std::end(kPaths), [&](const auto& p) { return name == p.first; });
}

Status importSampler(const tinygltf::Model& model, const tinygltf::AnimationSampler& gs, AnimationPath path,
                     uint32_t components, const std::string& where, const ReadFloats& read,
                     AnimationSampler* out) {
  out->components = components;
  if (gs.interpolation == "LINEAR" || gs.interpolation.empty()) {
    out->interpolation = Interpolation::Linear;
  } else if (gs.interpolation == "STEP") {
    out->interpolation = Interpolation::Step;
  } else if (gs.interpolation == "CUBICSPLINE") {
    out->interpolation = Interpolation::CubicSpline;
  } else {
    return malformed(where + ": unknown interpolation '" + gs.interpolation + "'");
  }
  const std::string iw = where + " input accessor " + str(gs.input);
  if (Status s = checkShape(model, gs.input, TINYGLTF_TYPE_SCALAR, false, iw); !s) return s;
  if (Status s = read(gs.input, iw, &out->times); !s) return s;
  if (out->times.empty()) return malformed(iw + ": no keyframes");
  for (size_t k = 0; k < out->times.size(); ++k) {
    if (!std::isfinite(out->times[k])) return malformed(iw + ": time " + str(uint64_t{k}) + " is not finite");
    if (k > 0 && !(out->times[k] > out->times[k - 1]))
      return malformed(iw + ": times are not strictly increasing (key " + str(uint64_t{k}) + ": " +
                       std::to_string(out->times[k]) + " after " + std::to_string(out->times[k - 1]) + ")");
  }
  const std::string ow = where + " output accessor " + str(gs.output);
  const bool vec = path != AnimationPath::Weights;
  const int type = !vec ? TINYGLTF_TYPE_SCALAR : components == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
  const bool normalizedOk = path == AnimationPath::Rotation || path == AnimationPath::Weights;
  if (Status s = checkShape(model, gs.output, type, normalizedOk, ow); !s) return s;
  if (Status s = read(gs.output, ow, &out->values); !s) return s;
  const bool cubic = out->interpolation == Interpolation::CubicSpline;
  const uint64_t perKey = uint64_t{components} * (cubic ? 3 : 1);
  if (out->values.size() != out->times.size() * perKey)
    return malformed(ow + ": " + str(uint64_t{out->values.size() / (vec ? components : 1)}) +
                     " elements for " + str(uint64_t{out->times.size()}) + " keys; " + gs.interpolation +
                     " needs " + str(uint64_t{perKey / (vec ? components : 1)}) + " per key");
  for (size_t i = 0; i < out->values.size(); ++i)
    if (!std::isfinite(out->values[i]))
      return malformed(ow + ": value " + str(uint64_t{i}) + " is not finite");
  return {};
}

// Components a channel's sampler produces: 3, 4, or the target mesh's morph target count (0: none).
uint32_t channelComponents(const tinygltf::Model& model, int node, AnimationPath path) {
  if (path == AnimationPath::Rotation) return 4;
  if (path != AnimationPath::Weights) return 3;
  const int mesh = model.nodes[static_cast<size_t>(node)].mesh;
  if (mesh < 0 || static_cast<size_t>(mesh) >= model.meshes.size()) return 0;
  const auto& prims = model.meshes[static_cast<size_t>(mesh)].primitives;
  return prims.empty() ? 0 : static_cast<uint32_t>(prims[0].targets.size());
}

Status importAnimation(const tinygltf::Model& model, size_t index, const std::string& path,
                       const ReadFloats& read, const Warn& warn, const std::vector<SceneNode>& nodes,
                       AnimationClip* clip) {
  const tinygltf::Animation& ga = model.animations[index];
  const std::string where = path + ": animation " + str(uint64_t{index}) + named(ga.name);
  clip->name = ga.name;
  std::map<int, uint32_t> samplers;  // glTF sampler index -> clip sampler index
  for (size_t ci = 0; ci < ga.channels.size(); ++ci) {
    const tinygltf::AnimationChannel& gc = ga.channels[ci];
    const std::string cw = where + " channel " + str(uint64_t{ci});
    AnimationChannel channel;
    if (gc.target_node < 0) {  // glTF: a channel without a target node is ignored
      warn(cw + ": no target node; ignored");
      continue;
    }
    if (!parsePath(gc.target_path, &channel.path)) {
      warn(cw + ": target path '" + gc.target_path + "' is not supported; ignored");
      continue;
    }
    if (static_cast<size_t>(gc.target_node) >= nodes.size())
      return malformed(cw + ": target node " + str(gc.target_node) + " does not exist");
    if (nodes[static_cast<size_t>(gc.target_node)].hasMatrix)
      return malformed(cw + ": target node " + str(gc.target_node) +
                       " has a matrix (animated nodes must use TRS)");
    if (gc.sampler < 0 || static_cast<size_t>(gc.sampler) >= ga.samplers.size())
      return malformed(cw + ": sampler " + str(gc.sampler) + " does not exist");
    const uint32_t components = channelComponents(model, gc.target_node, channel.path);
    if (components == 0) {
      warn(cw + ": weights target node " + str(gc.target_node) + " has no morph targets; ignored");
      continue;
    }
    channel.node = static_cast<uint32_t>(gc.target_node);
    auto [it, added] = samplers.emplace(gc.sampler, static_cast<uint32_t>(clip->samplers.size()));
    if (added) {
      AnimationSampler s;
      const std::string sw = where + " sampler " + str(gc.sampler);
      if (Status st = importSampler(model, ga.samplers[static_cast<size_t>(gc.sampler)], channel.path,
                                    components, sw, read, &s);
          !st)
        return st;
      clip->samplers.push_back(std::move(s));
    } else if (clip->samplers[it->second].components != components) {
      return malformed(cw + ": sampler " + str(gc.sampler) + " is shared by channels of different sizes");
    }
    channel.sampler = it->second;
    clip->channels.push_back(channel);
  }
  for (const AnimationSampler& s : clip->samplers)
    clip->duration = std::max(clip->duration, double(s.times.back()));
  return validateClip(*clip, nodes, where);
}

}  // namespace

Status convertSkinAttributes(const std::vector<float>& joints, const std::vector<float>& weights, int influences,
                             const std::string& where, const Warn& warn, SkinStreams* out) {
  const size_t n = static_cast<size_t>(influences);  // 4 or 8
  const size_t count = std::min(joints.size(), weights.size()) / n;
  out->joints.resize(count);
  out->weights.resize(count);
  out->joints1.assign(n == 8 ? count : 0, glm::u16vec4(0));
  out->weights1.assign(n == 8 ? count : 0, glm::vec4(0.0f));
  size_t unbound = 0;
  double w[8];
  for (size_t v = 0; v < count; ++v) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
      w[i] = weights[n * v + i];
      if (!std::isfinite(w[i]) || w[i] < -1e-6)  // tiny negatives are exporter rounding: clamp them to 0
        return malformed(where + ": vertex " + str(uint64_t{v}) + " has a negative or non-finite weight");
      w[i] = std::max(w[i], 0.0);
      sum += w[i];
    }
    // Normalised over every influence the vertex has (all 8 with JOINTS_1 / WEIGHTS_1), as glTF requires.
    if (sum > 0.0) {
      for (size_t i = 0; i < n; ++i) w[i] /= sum;
    } else {
      for (size_t i = 0; i < n; ++i) w[i] = i == 0 ? 1.0 : 0.0;
      ++unbound;
    }
    for (size_t i = 0; i < n; ++i) {
      const uint16_t joint = w[i] > 0.0 ? static_cast<uint16_t>(joints[n * v + i]) : uint16_t{0};
      const int slot = static_cast<int>(i % 4);
      (i < 4 ? out->weights[v] : out->weights1[v])[slot] = static_cast<float>(w[i]);
      (i < 4 ? out->joints[v] : out->joints1[v])[slot] = joint;
    }
  }
  if (unbound > 0)
    warn(where + ": " + str(uint64_t{unbound}) +
         " vertex(es) with all-zero weights follow their first joint slot");
  return {};
}

Status importAnimationData(const tinygltf::Model& model, const std::string& path, const ReadFloats& read,
                           const Warn& warn, ImportedScene* scene) {
  if (model.skins.empty() && model.animations.empty()) return {};
  if (Status s = importNodes(model, path, warn, &scene->nodes); !s) return s;
  if (Status s = importSkins(model, path, read, scene->nodes.size(), &scene->skins); !s) return s;
  for (size_t i = 0; i < model.animations.size(); ++i) {
    AnimationClip clip;
    if (Status s = importAnimation(model, i, path, read, warn, scene->nodes, &clip); !s) return s;
    scene->animations.push_back(std::move(clip));
  }
  return {};
}

Status checkSkinnedInstances(const ImportedScene& scene, const std::string& path) {
  std::set<std::pair<uint32_t, int32_t>> checked;  // (mesh, skin): instances repeat them
  for (const ImportedInstance& inst : scene.instances) {
    if (inst.skin < 0 || !checked.emplace(inst.mesh, inst.skin).second) continue;
    const MeshSource& m = scene.meshes[inst.mesh].source;
    const Skin& skin = scene.skins[static_cast<size_t>(inst.skin)];
    const std::string where = path + ": node " + str(inst.node) + " mesh '" + m.name + "' skin " +
                              str(inst.skin) + named(skin.name);
    if (m.joints.empty()) return malformed(where + ": the skinned mesh has no JOINTS_0 / WEIGHTS_0");
    for (size_t v = 0; v < m.joints.size(); ++v)
      for (int i = 0; i < 8; ++i) {
        if (i >= 4 && m.joints1.empty()) break;
        const float weight = i < 4 ? m.weights[v][i] : m.weights1[v][i - 4];
        const int joint = i < 4 ? m.joints[v][i] : m.joints1[v][i - 4];
        if (weight > 0.0f && static_cast<size_t>(joint) >= skin.joints.size())
          return malformed(where + ": vertex " + str(uint64_t{v}) + " uses joint index " + str(joint) +
                           ", not below the skin's joint count " + str(uint64_t{skin.joints.size()}) +
                           (i < 4 ? " (JOINTS_0)" : " (JOINTS_1)"));
      }
  }
  return {};
}

}  // namespace visbuf::gltf_detail
