// Section "rigidObjects" of a pack (pack_animation_format.h): Scene::rigidObjects, written as they are and read
// with every index and value checked before the scene holds it.
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "visbuf/asset/pack_animation.h"
#include "visbuf/asset/pack_animation_format.h"

namespace visbuf::pack {

void serializeRigidObjects(const Scene& scene, std::vector<SectionData>* out) {
  if (scene.rigidObjects.empty()) return;
  std::vector<uint8_t> bytes(scene.rigidObjects.size() * sizeof(RigidObjectRecord));
  for (size_t i = 0; i < scene.rigidObjects.size(); ++i) {
    const RigidObject& ro = scene.rigidObjects[i];
    RigidObjectRecord r{};
    r.object = ro.object;
    r.node = ro.node;
    r.clip = ro.clip;
    r.timeOffset = ro.timeOffset;
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) r.placement[c * 4 + k] = ro.placement[c][k];
    std::memcpy(bytes.data() + i * sizeof(r), &r, sizeof(r));
  }
  out->push_back({kRigidObjectsSection, sizeof(RigidObjectRecord), scene.rigidObjects.size(), std::move(bytes)});
}

Status readRigidObjects(const FindSection& find, const std::string& label, Scene* scene) {
  const SectionBytes s = find(kRigidObjectsSection);
  auto fail = [&](const std::string& message) {
    return makeError(ErrorCode::MalformedInput, label + ": section 'rigidObjects' " + message);
  };
  if (s.count > scene->objects.size())
    return fail(fmt::format("has {} records for {} objects", s.count, scene->objects.size()));
  std::vector<uint8_t> listed(scene->objects.size(), 0);
  for (const SkinnedObject& so : scene->skinnedObjects) listed[so.object] = 1;
  scene->rigidObjects.reserve(s.count);
  for (uint64_t i = 0; i < s.count; ++i) {
    RigidObjectRecord r;
    std::memcpy(&r, s.data + i * sizeof(r), sizeof(r));
    const std::string where = fmt::format("record {}", i);
    if (r.object >= scene->objects.size())
      return fail(fmt::format("{}: field 'object' {} out of range ({} objects)", where, r.object,
                              scene->objects.size()));
    if (r.node < 0 || uint64_t(r.node) >= scene->nodes.size())
      return fail(fmt::format("{}: field 'node' {} out of range ({} nodes)", where, r.node, scene->nodes.size()));
    if (r.clip < -1 || (r.clip >= 0 && uint64_t(r.clip) >= scene->animations.size()))
      return fail(fmt::format("{}: field 'clip' {} is not -1 or an animation index ({} animations)", where, r.clip,
                              scene->animations.size()));
    if (r.reserved != 0) return fail(where + ": field 'reserved' must be 0");
    if (!std::isfinite(r.timeOffset)) return fail(where + ": field 'timeOffset' is not finite");
    RigidObject ro{r.object, r.node, r.clip, r.timeOffset};
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) {
        const double v = r.placement[c * 4 + k];
        if (!std::isfinite(v)) return fail(where + ": field 'placement' is not finite");
        ro.placement[c][k] = v;
      }
    if (ro.placement[0][3] != 0.0 || ro.placement[1][3] != 0.0 || ro.placement[2][3] != 0.0 ||
        ro.placement[3][3] != 1.0)
      return fail(where + ": field 'placement' is not affine (last row must be 0 0 0 1)");
    if (listed[r.object]++)
      return fail(fmt::format("{}: object {} is listed twice or is a skinned object", where, r.object));
    scene->rigidObjects.push_back(ro);
  }
  return {};
}

}  // namespace visbuf::pack
