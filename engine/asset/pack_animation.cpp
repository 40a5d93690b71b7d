// The optional animation sections of a pack (pack_animation.h, pack_animation_format.h): serialisation and a
// reader that checks every index and range before copying, so a damaged file gives an Error, never an
// out-of-bounds read or an allocation larger than the file.
#include "visbuf/asset/pack_animation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "visbuf/asset/pack_animation_format.h"
#include "visbuf/asset/pack_geometry.h"

namespace visbuf::pack {

namespace {

template <typename T>
void append(std::vector<uint8_t>& out, const T& record) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &record, sizeof(T));
}

template <typename T>
void appendArray(std::vector<uint8_t>& out, const T* data, size_t count) {
  const size_t at = out.size();
  out.resize(at + count * sizeof(T));
  if (count > 0) std::memcpy(out.data() + at, data, count * sizeof(T));
}

void copyMatrix(const glm::dmat4& m, double* out) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[c * 4 + r] = m[c][r];
}
glm::dmat4 matrixOf(const double* v) {
  glm::dmat4 m;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = v[c * 4 + r];
  return m;
}

bool rangeFits(uint64_t offset, uint64_t size, uint64_t limit) {
  return offset <= limit && size <= limit - offset;
}
bool allFinite(const double* v, int n) {
  return std::all_of(v, v + n, [](double x) { return std::isfinite(x); });
}

// Accumulates serialised sections, skipping empty ones.
class Writer {
 public:
  explicit Writer(const AddString& addString) : addString_(addString) {}
  Result<StringRef> name(const std::string& s) { return addString_(s); }
  void section(const char* name, uint32_t elementSize, uint64_t count, std::vector<uint8_t> bytes) {
    if (count > 0) sections.push_back({name, elementSize, count, std::move(bytes)});
  }
  std::vector<SectionData> sections;

 private:
  const AddString& addString_;
};

Status writeNodes(const Scene& scene, Writer& w) {
  std::vector<uint8_t> bytes;
  for (const SceneNode& n : scene.nodes) {
    NodeRecord r{};
    auto name = w.name(n.name);
    if (!name) return name.error();
    r.name = *name;
    r.parent = n.parent;
    r.flags = n.hasMatrix ? kNodeHasMatrix : 0u;
    const glm::dquat& q = n.rest.rotation;
    for (int i = 0; i < 3; ++i) {
      r.translation[i] = n.rest.translation[i];
      r.scale[i] = n.rest.scale[i];
    }
    r.rotation[0] = q.x, r.rotation[1] = q.y, r.rotation[2] = q.z, r.rotation[3] = q.w;
    copyMatrix(n.matrix, r.matrix);
    append(bytes, r);
  }
  w.section(kNodesSection, sizeof(NodeRecord), scene.nodes.size(), std::move(bytes));
  return {};
}

Status writeSkins(const Scene& scene, Writer& w) {
  std::vector<uint8_t> skins, joints;
  uint64_t jointTotal = 0;
  for (const Skin& s : scene.skins) {
    auto name = w.name(s.name);
    if (!name) return name.error();
    append(skins, SkinRecord{*name, jointTotal, uint32_t(s.joints.size()), s.skeleton});
    for (size_t j = 0; j < s.joints.size(); ++j) {
      SkinJointRecord r{};
      r.node = s.joints[j];
      copyMatrix(s.inverseBindMatrices[j], r.inverseBind);
      append(joints, r);
    }
    jointTotal += s.joints.size();
  }
  w.section(kSkinsSection, sizeof(SkinRecord), scene.skins.size(), std::move(skins));
  w.section(kSkinJointsSection, sizeof(SkinJointRecord), jointTotal, std::move(joints));
  return {};
}

void writeSkinnedMeshes(const Scene& scene, Writer& w) {
  std::vector<uint8_t> meshes, vertices, objects;
  uint64_t meshCount = 0;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const std::vector<SkinVertex>& sv = scene.meshes[m].skinVertices;
    if (sv.empty()) continue;
    const std::vector<uint8_t> encoded = encodeVertexStream(sv.data(), sv.size(), sizeof(SkinVertex));
    append(meshes, SkinnedMeshRecord{uint32_t(m), 0, vertices.size(), encoded.size()});
    vertices.insert(vertices.end(), encoded.begin(), encoded.end());
    ++meshCount;
  }
  for (const SkinnedObject& so : scene.skinnedObjects)
    append(objects, SkinnedObjectRecord{so.object, so.skin});
  w.section(kSkinnedMeshesSection, sizeof(SkinnedMeshRecord), meshCount, std::move(meshes));
  const uint64_t encodedBytes = vertices.size();
  w.section(kSkinVerticesSection, 1, encodedBytes, std::move(vertices));
  w.section(kSkinnedObjectsSection, sizeof(SkinnedObjectRecord), scene.skinnedObjects.size(),
            std::move(objects));
}

void writeMorphTargets(const Scene& scene, Writer& w) {
  std::vector<uint8_t> meshes, deltas, weights, objects;
  uint64_t meshCount = 0, deltaTotal = 0, weightTotal = 0, objectCount = 0;
  for (size_t m = 0; m < scene.meshes.size(); ++m) {
    const Mesh& mesh = scene.meshes[m];
    if (mesh.morphTargetCount == 0) continue;
    append(meshes, MorphMeshRecord{uint32_t(m), mesh.morphTargetCount, deltaTotal, weightTotal});
    appendArray(deltas, mesh.morphDeltas.data(), mesh.morphDeltas.size());
    std::vector<float> defaults(mesh.morphTargetCount, 0.0f);
    std::copy_n(mesh.morphWeights.begin(), std::min<size_t>(defaults.size(), mesh.morphWeights.size()),
                defaults.begin());
    appendArray(weights, defaults.data(), defaults.size());
    ++meshCount;
    deltaTotal += mesh.morphDeltas.size();
    weightTotal += defaults.size();
  }
  for (size_t i = 0; i < scene.skinnedObjects.size(); ++i) {
    if (scene.skinnedObjects[i].morphNode < 0) continue;
    append(objects, MorphObjectRecord{uint32_t(i), uint32_t(scene.skinnedObjects[i].morphNode)});
    ++objectCount;
  }
  w.section(kMorphMeshesSection, sizeof(MorphMeshRecord), meshCount, std::move(meshes));
  w.section(kMorphDeltasSection, sizeof(gpu::MorphDelta), deltaTotal, std::move(deltas));
  w.section(kMorphWeightsSection, sizeof(float), weightTotal, std::move(weights));
  w.section(kMorphObjectsSection, sizeof(MorphObjectRecord), objectCount, std::move(objects));
}

Status writeAnimations(const Scene& scene, Writer& w) {
  std::vector<uint8_t> clips, samplers, channels, times, values;
  uint64_t samplerTotal = 0, channelTotal = 0, timeTotal = 0, valueTotal = 0;
  for (const AnimationClip& clip : scene.animations) {
    auto name = w.name(clip.name);
    if (!name) return name.error();
    append(clips,
           AnimationRecord{*name, clip.duration, uint32_t(samplerTotal), uint32_t(clip.samplers.size()),
                           uint32_t(channelTotal), uint32_t(clip.channels.size())});
    for (const AnimationSampler& s : clip.samplers) {
      append(samplers, AnimSamplerRecord{uint32_t(s.interpolation), s.components, timeTotal, s.times.size(),
                                         valueTotal});
      appendArray(times, s.times.data(), s.times.size());
      appendArray(values, s.values.data(), s.values.size());
      timeTotal += s.times.size();
      valueTotal += s.values.size();
    }
    for (const AnimationChannel& c : clip.channels)
      append(channels, AnimChannelRecord{c.sampler, c.node, uint32_t(c.path), 0});
    samplerTotal += clip.samplers.size();
    channelTotal += clip.channels.size();
  }
  if (samplerTotal > UINT32_MAX || channelTotal > UINT32_MAX)
    return makeError(ErrorCode::CapacityExceeded, "more than 2^32-1 animation samplers or channels");
  w.section(kAnimationsSection, sizeof(AnimationRecord), scene.animations.size(), std::move(clips));
  w.section(kAnimSamplersSection, sizeof(AnimSamplerRecord), samplerTotal, std::move(samplers));
  w.section(kAnimChannelsSection, sizeof(AnimChannelRecord), channelTotal, std::move(channels));
  w.section(kAnimTimesSection, sizeof(float), timeTotal, std::move(times));
  w.section(kAnimValuesSection, sizeof(float), valueTotal, std::move(values));
  return {};
}

// --- reading

class Reader {
 public:
  Reader(const FindSection& find, const ReadString& readString, const std::string& label, Scene* scene)
      : find_(find), readString_(readString), label_(label), scene_(*scene) {}
  Status readNodes();
  Status readSkins();
  Status readSkinnedMeshes();
  Status readSkinnedObjects();
  Status readMorphTargets();
  Status readAnimations();

 private:
  Error fail(const std::string& message) const {
    return makeError(ErrorCode::MalformedInput, label_ + ": " + message);
  }
  template <typename T>
  static T record(const SectionBytes& s, uint64_t i) {  // caller guarantees i < s.count
    T r;
    std::memcpy(&r, s.data + i * sizeof(T), sizeof(T));
    return r;
  }
  // "fields 'first' F + 'count' C run past the N records of section 'S'" unless the range fits.
  Status checkRange(const std::string& where, const char* first, uint64_t firstValue, const char* count,
                    uint64_t countValue, const char* section) const {
    const uint64_t limit = find_(section).count;
    if (rangeFits(firstValue, countValue, limit)) return {};
    return fail(fmt::format("{}: fields '{}' {} + '{}' {} run past the {} records of section '{}'", where,
                            first, firstValue, count, countValue, limit, section));
  }
  Status readSampler(const AnimSamplerRecord& r, const std::string& where, AnimationSampler* out);

  const FindSection& find_;
  const ReadString& readString_;
  const std::string& label_;
  Scene& scene_;
};

Status Reader::readNodes() {
  const SectionBytes s = find_(kNodesSection);
  scene_.nodes.resize(s.count);
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<NodeRecord>(s, i);
    const std::string where = fmt::format("section 'nodes' record {}", i);
    auto name = readString_(r.name, where + " field 'name'");
    if (!name) return name.error();
    if (r.parent < -1 || (r.parent >= 0 && uint64_t(r.parent) >= s.count))
      return fail(
          fmt::format("{}: field 'parent' {} is not -1 or a node index (< {})", where, r.parent, s.count));
    if ((r.flags & ~kNodeHasMatrix) != 0)
      return fail(fmt::format("{}: field 'flags' {:#x} has unknown bits", where, r.flags));
    if (!allFinite(r.translation, 3) || !allFinite(r.rotation, 4) || !allFinite(r.scale, 3) ||
        !allFinite(r.matrix, 16))
      return fail(where + ": non-finite transform");
    SceneNode& n = scene_.nodes[i];
    n.name = *name;
    n.parent = r.parent;
    n.hasMatrix = (r.flags & kNodeHasMatrix) != 0;
    n.rest.translation = {r.translation[0], r.translation[1], r.translation[2]};
    n.rest.rotation = glm::dquat(r.rotation[3], r.rotation[0], r.rotation[1], r.rotation[2]);
    n.rest.scale = {r.scale[0], r.scale[1], r.scale[2]};
    n.matrix = matrixOf(r.matrix);
  }
  if (Status st = validateNodes(scene_.nodes); !st) return fail("section 'nodes': " + st.error().message);
  return {};
}

Status Reader::readSkins() {
  const SectionBytes s = find_(kSkinsSection);
  const SectionBytes joints = find_(kSkinJointsSection);
  uint64_t used = 0;  // joint records referenced so far: at most the section's count (no amplification)
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<SkinRecord>(s, i);
    const std::string where = fmt::format("section 'skins' record {}", i);
    auto name = readString_(r.name, where + " field 'name'");
    if (!name) return name.error();
    if (r.jointCount == 0 || r.jointCount > 65536)
      return fail(fmt::format("{}: field 'jointCount' is {} (1..65536)", where, r.jointCount));
    if (Status st =
            checkRange(where, "firstJoint", r.firstJoint, "jointCount", r.jointCount, kSkinJointsSection);
        !st)
      return st;
    used += r.jointCount;
    if (used > joints.count)
      return fail(where + ": skins reference more joints than section 'skinJoints' holds");
    Skin skin;
    skin.name = *name;
    skin.skeleton = r.skeleton;
    for (uint32_t j = 0; j < r.jointCount; ++j) {
      const auto jr = record<SkinJointRecord>(joints, r.firstJoint + j);
      if (!allFinite(jr.inverseBind, 16))
        return fail(fmt::format("{} joint {}: field 'inverseBind' is not finite", where, j));
      skin.joints.push_back(jr.node);
      skin.inverseBindMatrices.push_back(matrixOf(jr.inverseBind));
    }
    if (Status st = validateSkin(skin, scene_.nodes.size(), where); !st) return fail(st.error().message);
    scene_.skins.push_back(std::move(skin));
  }
  return {};
}

Status Reader::readSkinnedMeshes() {
  const SectionBytes s = find_(kSkinnedMeshesSection);
  const SectionBytes vertices = find_(kSkinVerticesSection);
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<SkinnedMeshRecord>(s, i);
    const std::string where = fmt::format("section 'skinnedMeshes' record {}", i);
    if (r.mesh >= scene_.meshes.size())
      return fail(
          fmt::format("{}: field 'mesh' {} out of range ({} meshes)", where, r.mesh, scene_.meshes.size()));
    if (r.reserved != 0) return fail(where + ": field 'reserved' must be 0");
    Mesh& mesh = scene_.meshes[r.mesh];
    if (!mesh.skinVertices.empty()) return fail(fmt::format("{}: mesh {} is listed twice", where, r.mesh));
    if (r.byteCount == 0) return fail(where + ": field 'byteCount' is 0");
    if (Status st = checkRange(where, "firstByte", r.firstByte, "byteCount", r.byteCount, kSkinVerticesSection); !st)
      return st;
    const uint64_t count = mesh.vertices.size();
    // The vertex codec expands its input at most 64x (pack_reader.cpp): a stream that claims more is refused
    // before the allocation, so a small hostile section cannot ask for gigabytes. byteCount fits in the file.
    if (count * sizeof(SkinVertex) > r.byteCount * 64)
      return fail(fmt::format("{}: {} encoded bytes cannot hold the mesh's {} skin vertices", where, r.byteCount,
                              count));
    mesh.skinVertices.resize(count);
    const std::string error = decodeVertexStream(mesh.skinVertices.data(), count, sizeof(SkinVertex),
                                                 vertices.data + r.firstByte, r.byteCount);
    if (!error.empty()) {
      mesh.skinVertices.clear();
      return fail(fmt::format("{}: skin vertices of mesh {} do not decode: {}", where, r.mesh, error));
    }
  }
  return {};
}

Status Reader::readSkinnedObjects() {
  const SectionBytes s = find_(kSkinnedObjectsSection);
  if (s.count > scene_.objects.size())
    return fail(
        fmt::format("section 'skinnedObjects': {} records for {} objects", s.count, scene_.objects.size()));
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<SkinnedObjectRecord>(s, i);
    if (r.object >= scene_.objects.size() || r.skin >= scene_.skins.size())
      return fail(
          fmt::format("section 'skinnedObjects' record {}: field 'object' {} / 'skin' {} out of range ({} "
                      "objects, {} skins)",
                      i, r.object, r.skin, scene_.objects.size(), scene_.skins.size()));
    scene_.skinnedObjects.push_back({r.object, r.skin});
  }
  return {};
}

Status Reader::readMorphTargets() {
  const SectionBytes s = find_(kMorphMeshesSection);
  const SectionBytes deltas = find_(kMorphDeltasSection), weights = find_(kMorphWeightsSection);
  uint64_t deltasUsed = 0, weightsUsed = 0;  // no amplification: every record range is counted once
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<MorphMeshRecord>(s, i);
    const std::string where = fmt::format("section 'morphMeshes' record {}", i);
    if (r.mesh >= scene_.meshes.size())
      return fail(fmt::format("{}: field 'mesh' {} out of range ({} meshes)", where, r.mesh, scene_.meshes.size()));
    Mesh& mesh = scene_.meshes[r.mesh];
    if (mesh.morphTargetCount != 0) return fail(fmt::format("{}: mesh {} is listed twice", where, r.mesh));
    if (r.targetCount == 0 || r.targetCount > 65536)
      return fail(fmt::format("{}: field 'targetCount' is {} (1..65536)", where, r.targetCount));
    const uint64_t count = uint64_t(r.targetCount) * mesh.vertices.size();  // < 2^16 x 2^32: no overflow
    if (Status st = checkRange(where, "firstDelta", r.firstDelta, "targetCount x vertexCount", count,
                               kMorphDeltasSection);
        !st)
      return st;
    if (Status st =
            checkRange(where, "firstWeight", r.firstWeight, "targetCount", r.targetCount, kMorphWeightsSection);
        !st)
      return st;
    deltasUsed += count;
    weightsUsed += r.targetCount;
    if (deltasUsed > deltas.count || weightsUsed > weights.count)
      return fail(where + ": meshes reference more deltas or weights than sections 'morphDeltas' / 'morphWeights' hold");
    mesh.morphTargetCount = r.targetCount;
    mesh.morphDeltas.resize(count);
    std::memcpy(mesh.morphDeltas.data(), deltas.data + r.firstDelta * sizeof(gpu::MorphDelta),
                count * sizeof(gpu::MorphDelta));
    mesh.morphWeights.resize(r.targetCount);
    std::memcpy(mesh.morphWeights.data(), weights.data + r.firstWeight * sizeof(float), r.targetCount * sizeof(float));
    for (uint64_t d = 0; d < count; ++d) {
      const gpu::MorphDelta& m = mesh.morphDeltas[d];
      for (float f : {m.px, m.py, m.pz, m.nx, m.ny, m.nz, m.tx, m.ty, m.tz})
        if (!std::isfinite(f))
          return fail(fmt::format("{}: delta {} (section 'morphDeltas' record {}) is not finite", where, d,
                                  r.firstDelta + d));
    }
    for (uint32_t t = 0; t < r.targetCount; ++t)
      if (!std::isfinite(mesh.morphWeights[t]))
        return fail(fmt::format("{}: default weight {} (section 'morphWeights' record {}) is not finite", where, t,
                                r.firstWeight + t));
  }
  const SectionBytes objects = find_(kMorphObjectsSection);
  for (uint64_t i = 0; i < objects.count; ++i) {
    const auto r = record<MorphObjectRecord>(objects, i);
    const std::string where = fmt::format("section 'morphObjects' record {}", i);
    if (r.skinnedObject >= scene_.skinnedObjects.size() || r.node >= scene_.nodes.size())
      return fail(fmt::format("{}: field 'skinnedObject' {} / 'node' {} out of range ({} skinned objects, {} nodes)",
                              where, r.skinnedObject, r.node, scene_.skinnedObjects.size(), scene_.nodes.size()));
    SkinnedObject& so = scene_.skinnedObjects[r.skinnedObject];
    if (so.morphNode >= 0)
      return fail(fmt::format("{}: skinned object {} is listed twice", where, r.skinnedObject));
    if (scene_.meshes[scene_.objects[so.object].mesh].morphTargetCount == 0)
      return fail(fmt::format("{}: skinned object {} draws mesh {}, which has no 'morphMeshes' record", where,
                              r.skinnedObject, scene_.objects[so.object].mesh));
    so.morphNode = int32_t(r.node);
  }
  return {};
}

Status Reader::readSampler(const AnimSamplerRecord& r, const std::string& where, AnimationSampler* out) {
  if (r.interpolation > uint32_t(Interpolation::CubicSpline))
    return fail(fmt::format("{}: field 'interpolation' is {} (0 linear, 1 step, 2 cubic spline)", where,
                            r.interpolation));
  if (r.components == 0 || r.components > 65536)
    return fail(fmt::format("{}: field 'components' is {} (1..65536)", where, r.components));
  if (r.keyCount == 0) return fail(where + ": field 'keyCount' is 0");
  if (Status st = checkRange(where, "firstTime", r.firstTime, "keyCount", r.keyCount, kAnimTimesSection); !st)
    return st;
  // keyCount <= the section's count (< 2^62 records), components <= 2^16, x3: no overflow.
  const uint64_t valueCount =
      r.keyCount * r.components * (r.interpolation == uint32_t(Interpolation::CubicSpline) ? 3 : 1);
  if (Status st =
          checkRange(where, "firstValue", r.firstValue, "value count", valueCount, kAnimValuesSection);
      !st)
    return st;
  const SectionBytes times = find_(kAnimTimesSection), values = find_(kAnimValuesSection);
  out->interpolation = Interpolation(r.interpolation);
  out->components = r.components;
  out->times.resize(r.keyCount);
  std::memcpy(out->times.data(), times.data + r.firstTime * sizeof(float), r.keyCount * sizeof(float));
  out->values.resize(valueCount);
  std::memcpy(out->values.data(), values.data + r.firstValue * sizeof(float), valueCount * sizeof(float));
  return {};
}

Status Reader::readAnimations() {
  const SectionBytes s = find_(kAnimationsSection);
  const SectionBytes samplers = find_(kAnimSamplersSection), channels = find_(kAnimChannelsSection);
  uint64_t samplersUsed = 0, channelsUsed = 0, timesUsed = 0, valuesUsed = 0;
  for (uint64_t i = 0; i < s.count; ++i) {
    const auto r = record<AnimationRecord>(s, i);
    const std::string where = fmt::format("section 'animations' record {}", i);
    auto name = readString_(r.name, where + " field 'name'");
    if (!name) return name.error();
    if (Status st = checkRange(where, "firstSampler", r.firstSampler, "samplerCount", r.samplerCount,
                               kAnimSamplersSection);
        !st)
      return st;
    if (Status st = checkRange(where, "firstChannel", r.firstChannel, "channelCount", r.channelCount,
                               kAnimChannelsSection);
        !st)
      return st;
    samplersUsed += r.samplerCount;
    channelsUsed += r.channelCount;
    if (samplersUsed > samplers.count || channelsUsed > channels.count)
      return fail(where + ": clips reference more samplers or channels than their sections hold");
    AnimationClip clip;
    clip.name = *name;
    clip.duration = r.duration;
    for (uint32_t k = 0; k < r.samplerCount; ++k) {
      const auto sr = record<AnimSamplerRecord>(samplers, uint64_t{r.firstSampler} + k);
      AnimationSampler sampler;
      const std::string sw = fmt::format("{} sampler {} (section 'animSamplers' record {})", where, k,
                                         uint64_t{r.firstSampler} + k);
      if (Status st = readSampler(sr, sw, &sampler); !st) return st;
      timesUsed += sampler.times.size();
      valuesUsed += sampler.values.size();
      if (timesUsed > find_(kAnimTimesSection).count || valuesUsed > find_(kAnimValuesSection).count)
        return fail(sw +
                    ": samplers reference more keys or values than sections 'animTimes' / 'animValues' hold");
      clip.samplers.push_back(std::move(sampler));
    }
    for (uint32_t k = 0; k < r.channelCount; ++k) {
      const auto cr = record<AnimChannelRecord>(channels, uint64_t{r.firstChannel} + k);
      const std::string cw = fmt::format("{} channel {} (section 'animChannels' record {})", where, k,
                                         uint64_t{r.firstChannel} + k);
      if (cr.sampler >= r.samplerCount || cr.node >= scene_.nodes.size() ||
          cr.path > uint32_t(AnimationPath::Weights))
        return fail(
            fmt::format("{}: field 'sampler' {} / 'node' {} / 'path' {} out of range ({} samplers, {} nodes, "
                        "paths 0..3)",
                        cw, cr.sampler, cr.node, cr.path, r.samplerCount, scene_.nodes.size()));
      clip.channels.push_back({cr.sampler, cr.node, AnimationPath(cr.path)});
    }
    if (Status st = validateClip(clip, scene_.nodes, where); !st) return fail(st.error().message);
    scene_.animations.push_back(std::move(clip));
  }
  return {};
}

}  // namespace

uint32_t animationSectionElementSize(const std::string& name) {
  static const std::pair<const char*, uint32_t> kSizes[] = {
      {kNodesSection, sizeof(NodeRecord)},
      {kSkinsSection, sizeof(SkinRecord)},
      {kSkinJointsSection, sizeof(SkinJointRecord)},
      {kSkinnedMeshesSection, sizeof(SkinnedMeshRecord)},
      {kSkinVerticesSection, 1},
      {kSkinnedObjectsSection, sizeof(SkinnedObjectRecord)},
      {kMorphMeshesSection, sizeof(MorphMeshRecord)},
      {kMorphDeltasSection, sizeof(gpu::MorphDelta)},
      {kMorphWeightsSection, sizeof(float)},
      {kMorphObjectsSection, sizeof(MorphObjectRecord)},
      {kAnimationsSection, sizeof(AnimationRecord)},
      {kAnimSamplersSection, sizeof(AnimSamplerRecord)},
      {kAnimChannelsSection, sizeof(AnimChannelRecord)},
      {kAnimTimesSection, sizeof(float)},
      {kAnimValuesSection, sizeof(float)},
      {kRigidObjectsSection, sizeof(RigidObjectRecord)},
      {kCamerasSection, sizeof(CameraRecord)}};
  for (const auto& [section, size] : kSizes)
    if (name == section) return size;
  return 0;
}

Result<std::vector<SectionData>> serializeAnimationSections(const Scene& scene, const AddString& addString) {
  Writer w(addString);
  if (Status s = writeNodes(scene, w); !s) return s.error();
  if (Status s = writeSkins(scene, w); !s) return s.error();
  writeSkinnedMeshes(scene, w);
  writeMorphTargets(scene, w);
  if (Status s = writeAnimations(scene, w); !s) return s.error();
  serializeRigidObjects(scene, &w.sections);
  if (Status s = serializeCameras(scene, addString, &w.sections); !s) return s.error();
  return std::move(w.sections);
}

Status readAnimationSections(const FindSection& find, const ReadString& readString, const std::string& label,
                             Scene* scene) {
  Reader r(find, readString, label, scene);
  if (Status s = r.readNodes(); !s) return s;
  if (Status s = r.readSkins(); !s) return s;
  if (Status s = r.readSkinnedMeshes(); !s) return s;
  if (Status s = r.readSkinnedObjects(); !s) return s;
  if (Status s = r.readMorphTargets(); !s) return s;
  if (Status s = r.readAnimations(); !s) return s;
  if (Status s = readRigidObjects(find, label, scene); !s) return s;
  return readCameras(find, readString, label, scene);
}

}  // namespace visbuf::pack
