// Internal to engine/asset: writing and reading the optional animation sections of a pack
// (pack_animation_format.h). The pack writer and reader call these; the section table, checksums and
// strings stay theirs. Not installed as public API.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "visbuf/asset/pack_format.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf::pack {

// One serialised section, ready for the writer's table.
struct SectionData {
  const char* name;
  uint32_t elementSize;
  uint64_t count;
  std::vector<uint8_t> bytes;
};

// Record size of an animation section name, 0 for any other name.
uint32_t animationSectionElementSize(const std::string& name);

using AddString = std::function<Result<StringRef>(const std::string&)>;
// The animation sections of `scene` (only those with at least one record; none for a static scene).
// The scene has passed validateScene().
Result<std::vector<SectionData>> serializeAnimationSections(const Scene& scene, const AddString& addString);

// A section as the reader found it (range- and checksum-checked): `count` records at `data`.
struct SectionBytes {
  const uint8_t* data = nullptr;
  uint64_t count = 0;  // 0 when the section is absent
};
using FindSection = std::function<SectionBytes(const char* name)>;
using ReadString = std::function<Result<std::string>(StringRef ref, const std::string& where)>;
// Reads the animation sections into `scene` (whose meshes and objects are already read), checking every
// index, range and value; messages start with `label` and name section, record and field.
Status readAnimationSections(const FindSection& find, const ReadString& readString, const std::string& label,
                             Scene* scene);

// Section "rigidObjects" (pack_rigid.cpp), called by serializeAnimationSections / readAnimationSections: the
// section of scene.rigidObjects (none when empty), and the reader, after nodes, clips and skinned objects are
// read, checking every record's object, node and clip index, time offset and placement.
void serializeRigidObjects(const Scene& scene, std::vector<SectionData>* out);
Status readRigidObjects(const FindSection& find, const std::string& label, Scene* scene);

// Section "cameras" (pack_cameras.cpp), written and read with the animation sections: Scene::cameras and the
// default camera's projection (none for a scene without cameras whose default camera is an infinite perspective
// with the viewport's aspect); the reader checks every camera with validateCamera().
Status serializeCameras(const Scene& scene, const AddString& addString, std::vector<SectionData>* out);
Status readCameras(const FindSection& find, const ReadString& readString, const std::string& label, Scene* scene);

}  // namespace visbuf::pack
