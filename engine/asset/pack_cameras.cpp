// Section "cameras" of a pack (pack_animation_format.h): Scene::cameras and the default camera's projection,
// written as they are and read with every value checked (validateCamera) before the scene holds it.
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "visbuf/asset/pack_animation.h"
#include "visbuf/asset/pack_animation_format.h"

namespace visbuf::pack {

namespace {
constexpr uint32_t kDefaultCameraFlag = 1;

// The fields a CameraRecord and a Camera share, copied either way (the vectors element by element).
template <typename From, typename To>
void copyCameraFields(const From& from, To& to) {
  for (int i = 0; i < 3; ++i) {
    to.position[i] = from.position[i];
    to.target[i] = from.target[i];
    to.up[i] = from.up[i];
  }
  to.fovY = from.fovY;
  to.nearPlane = from.nearPlane;
  to.farPlane = from.farPlane;
  to.aspectRatio = from.aspectRatio;
  to.xmag = from.xmag;
  to.ymag = from.ymag;
}

CameraRecord recordOf(const Camera& c) {
  CameraRecord r{};
  r.projection = uint32_t(c.projection);
  copyCameraFields(c, r);
  return r;
}

Camera cameraOf(const CameraRecord& r) {
  Camera c;
  c.projection = Projection(r.projection);
  copyCameraFields(r, c);
  return c;
}

// What the "scene" record alone says of a camera: an infinite perspective with the viewport's aspect.
bool plainPerspective(const Camera& c) {
  const Camera plain;
  return c.projection == Projection::Perspective && c.farPlane == plain.farPlane && c.aspectRatio == 0.0 &&
         c.xmag == plain.xmag && c.ymag == plain.ymag;
}
}  // namespace

Status serializeCameras(const Scene& scene, const AddString& addString, std::vector<SectionData>* out) {
  const bool withDefault = !plainPerspective(scene.defaultCamera);
  if (scene.cameras.empty() && !withDefault) return {};
  if (!(scene.defaultCamera.nearPlane > 0.0))  // (the "scene" record's near plane must be a positive distance)
    return makeError(ErrorCode::InvalidArgument,
                     "pack: the default camera's near plane is 0 (orthographic); a pack stores a positive one");
  std::vector<uint8_t> bytes;
  auto add = [&](const CameraRecord& r) {
    const size_t at = bytes.size();
    bytes.resize(at + sizeof(r));
    std::memcpy(bytes.data() + at, &r, sizeof(r));
  };
  for (const NamedCamera& nc : scene.cameras) {
    CameraRecord r = recordOf(nc.camera);
    auto name = addString(nc.name);
    if (!name) return name.error();
    r.name = *name;
    add(r);
  }
  if (withDefault) {
    CameraRecord r = recordOf(scene.defaultCamera);
    r.flags = kDefaultCameraFlag;
    add(r);
  }
  const uint64_t count = bytes.size() / sizeof(CameraRecord);
  out->push_back({kCamerasSection, sizeof(CameraRecord), count, std::move(bytes)});
  return {};
}

Status readCameras(const FindSection& find, const ReadString& readString, const std::string& label, Scene* scene) {
  const SectionBytes s = find(kCamerasSection);
  auto fail = [&](const std::string& message) {
    return makeError(ErrorCode::MalformedInput, label + ": section 'cameras' " + message);
  };
  bool sawDefault = false;
  for (uint64_t i = 0; i < s.count; ++i) {
    CameraRecord r;
    std::memcpy(&r, s.data + i * sizeof(r), sizeof(r));
    const std::string where = fmt::format("record {}", i);
    if (r.flags & ~kDefaultCameraFlag) return fail(where + ": field 'flags' has unknown bits");
    if (r.projection > uint32_t(Projection::Orthographic))
      return fail(fmt::format("{}: field 'projection' {} is not 0 or 1", where, r.projection));
    Camera c = cameraOf(r);
    if (Status v = validateCamera(c); !v) return fail(where + ": " + v.error().message);
    if (r.flags & kDefaultCameraFlag) {
      if (sawDefault || i + 1 != s.count) return fail(where + ": the default camera's record must be the last, once");
      sawDefault = true;
      // The pose stays the "scene" record's; the projection is this one's.
      c.position = scene->defaultCamera.position;
      c.target = scene->defaultCamera.target;
      c.up = scene->defaultCamera.up;
      if (c.fovY != scene->defaultCamera.fovY || c.nearPlane != scene->defaultCamera.nearPlane)
        return fail(where + ": the default camera's fovY / near differ from the 'scene' record's");
      scene->defaultCamera = c;
      continue;
    }
    auto name = readString(r.name, "section 'cameras' " + where + " field 'name'");
    if (!name) return name.error();
    scene->cameras.push_back({std::move(*name), c});
  }
  return {};
}

}  // namespace visbuf::pack
