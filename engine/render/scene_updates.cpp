// Scenes that change between frames: moved, hidden, added and removed objects. The renderer keeps the scene's
// objects (plus RendererConfig::spareObjects free slots) on the CPU; a change rewrites the CPU record at once and
// marks the object, and the next frame's setup command buffer copies the marked records from the frame slot's
// staging buffer into the object buffer. Nothing else is uploaded.
//
// Occlusion history stays conservative without any change to it: a moved object is tested where it is now (the
// early phase redraws last frame's visible set at their new places; everything else meets the late test), a
// hidden or removed object is skipped by the cull pass (OBJECT_FLAG_HIDDEN), and a slot reused by a new object
// keeps its old visibility bit, which at worst draws it in the early phase for one frame.
#include "visbuf/render/renderer_impl.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <fmt/format.h>

namespace visbuf {

void Renderer::Impl::markDirty(uint32_t id) { markDirty(id, objectRecord(id)); }

void Renderer::Impl::markDirty(uint32_t id, const gpu::ObjectData& record) {
  if (dirtyIndex[id]) {
    dirtyRecords[dirtyIndex[id] - 1] = record;
    return;
  }
  dirty.push_back(id);
  dirtyRecords.push_back(record);
  dirtyIndex[id] = uint32_t(dirty.size());
}

// The GPU record of an object ID: its packed object (a skinned instance: its placement and mesh slot), with
// OBJECT_FLAG_HIDDEN when hidden; a free slot is a hidden record of nothing.
gpu::ObjectData Renderer::Impl::objectRecord(uint32_t id) const {
  gpu::ObjectData d{};
  if (slotState[id] == SlotFree) {
    d.flags = OBJECT_FLAG_HIDDEN | 15u << OBJECT_DRAW_LIST_SHIFT;
    return d;
  }
  d = packObject(objects[id], scene);
  if (skinnedObject[id])
    for (size_t k = 0; k < gpuScene.skinned.size(); ++k)
      if (gpuScene.skinned[k].object == id) {
        d = packSkinnedObject(objects[id], scene.skinnedObjects[k].placement, scene);
        d.meshIndex = gpuScene.skinned[k].meshSlot;
      }
  if (slotState[id] == SlotHidden) d.flags |= OBJECT_FLAG_HIDDEN;
  return d;
}

Status Renderer::Impl::checkTransform(uint32_t id, const glm::dmat4& m, const char* what) const {
  if (!isLive(id))
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("{}: object {} is not a live object (IDs below {}, not removed)", what, id,
                                 slotState.size()));
  if (skinnedObject[id])
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("{}: object {} is skinned: its pose and placement place it", what, id));
  if (rigidObject[id])
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("{}: object {} is node-animated: FrameOptions::animationTime places it", what, id));
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r]))
        return makeError(ErrorCode::InvalidArgument,
                         fmt::format("{}: object {}: the transform has a non-finite element", what, id));
  const double det = glm::determinant(glm::dmat3(m));
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    return makeError(ErrorCode::InvalidArgument, fmt::format("{}: object {}: the transform is singular", what, id));
  return {};
}

Status Renderer::setTransforms(std::span<const ObjectTransform> moves) {
  return impl_->guarded([&]() -> Status {
    Impl& r = *impl_;
    // All or nothing: every move is checked (draw-list room included) before any is applied.
    std::array<uint32_t, DRAW_LISTS> live = r.listLive;
    std::vector<gpu::ObjectData> records(moves.size());  // packed now, while the objects are in cache
    for (size_t i = 0; i < moves.size(); ++i) {
      const ObjectTransform& m = moves[i];
      if (Status s = r.checkTransform(m.object, m.transform, "setTransforms"); !s.ok()) return s;
      Object moved = r.objects[m.object];
      moved.transform = m.transform;
      records[i] = packObject(moved, r.scene);
      if (r.slotState[m.object] == Impl::SlotHidden) records[i].flags |= OBJECT_FLAG_HIDDEN;
      const uint32_t list = gpu::objectDrawList(records[i].flags);
      const uint32_t from = r.gpuScene.objectList[m.object];
      if (list == from) continue;
      // The winding flipped: the object changes draw list; a list the micro-raster fills from its end must have room.
      if (list != DRAW_LIST_NONE && (r.swListMask >> list & 1u) && live[list] >= r.listObjectCapacity(list))
        return makeError(ErrorCode::CapacityExceeded,
                         fmt::format("setTransforms: object {} flips its winding into draw list {}, which is full "
                                     "(capacity {}); reserve RendererConfig::spareObjects",
                                     m.object, list, r.listObjectCapacity(list)));
      if (from != DRAW_LIST_NONE) --live[from];
      if (list != DRAW_LIST_NONE) ++live[list];
    }
    for (size_t i = 0; i < moves.size(); ++i) {
      r.objects[moves[i].object].transform = moves[i].transform;
      r.gpuScene.objectList[moves[i].object] = gpu::objectDrawList(records[i].flags);
      r.markDirty(moves[i].object, records[i]);
    }
    r.listLive = live;
    return {};
  });
}

Status Renderer::setVisible(uint32_t object, bool visible) {
  return impl_->guarded([&]() -> Status {
    Impl& r = *impl_;
    if (!r.isLive(object))
      return makeError(ErrorCode::InvalidArgument, fmt::format("setVisible: object {} is not a live object", object));
    const uint8_t state = visible ? Impl::SlotLive : Impl::SlotHidden;
    if (r.slotState[object] == state) return {};
    r.slotState[object] = state;
    r.markDirty(object);
    return {};
  });
}

Result<uint32_t> Renderer::addObject(const Object& object) {
  return impl_->guarded([&]() -> Result<uint32_t> {
    Impl& r = *impl_;
    if (object.mesh >= r.scene.meshes.size())
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("addObject: mesh {} (the scene has {})", object.mesh, r.scene.meshes.size()));
    if (object.material >= r.scene.materials.size())
      return makeError(ErrorCode::InvalidArgument, fmt::format("addObject: material {} (the scene has {})",
                                                               object.material, r.scene.materials.size()));
    if (r.freeSlots.empty())
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("addObject: no free object slot ({} in use); create the renderer with more "
                                   "RendererConfig::spareObjects",
                                   r.slotState.size()));
    const uint32_t id = r.freeSlots.back();
    r.slotState[id] = Impl::SlotLive;  // (for checkTransform; undone below on refusal)
    Status s = r.checkTransform(id, object.transform, "addObject");
    const uint32_t list = gpu::objectDrawList(packObject(object, r.scene).flags);
    if (s.ok() && list != DRAW_LIST_NONE && r.listLive[list] >= r.listObjectCapacity(list))
      s = makeError(ErrorCode::CapacityExceeded, fmt::format("addObject: draw list {} is full (capacity {})", list,
                                                              r.listObjectCapacity(list)));
    if (!s.ok()) {
      r.slotState[id] = Impl::SlotFree;
      return s.error();
    }
    r.freeSlots.pop_back();
    r.objects[id] = object;
    r.gpuScene.objectMesh[id] = object.mesh;
    r.gpuScene.objectList[id] = list;
    if (list != DRAW_LIST_NONE) {
      ++r.listLive[list];
    } else {
      if (!r.transparent.created()) {
        r.transparent = passes::TransparentPass::create(r.device, r.sceneSets.layout(), r.textured);
        r.transparent.bind(r.boundLights(), r.boundLightTiles());
      }
      r.blendObjects.push_back(id);
    }
    r.markDirty(id);
    return id;
  });
}

Status Renderer::removeObject(uint32_t object) {
  return impl_->guarded([&]() -> Status {
    Impl& r = *impl_;
    if (!r.isLive(object))
      return makeError(ErrorCode::InvalidArgument, fmt::format("removeObject: object {} is not a live object", object));
    if (r.skinnedObject[object])
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("removeObject: object {} is skinned (hide it with setVisible)", object));
    const uint32_t list = r.gpuScene.objectList[object];
    if (list != DRAW_LIST_NONE)
      --r.listLive[list];
    else
      r.blendObjects.erase(std::remove(r.blendObjects.begin(), r.blendObjects.end(), object), r.blendObjects.end());
    r.slotState[object] = Impl::SlotFree;
    r.rigidObject[object] = 0;  // a new object in this slot is the host's to place
    r.gpuScene.objectList[object] = DRAW_LIST_NONE;
    r.freeSlots.push_back(object);
    std::sort(r.freeSlots.rbegin(), r.freeSlots.rend());  // the lowest free ID is reused first
    r.markDirty(object);
    return {};
  });
}

void Renderer::Impl::poseRigidObjects(double time) {
  if (scene.rigidObjects.empty() || (rigidPosed && time == rigidTime)) return;
  rigidPosed = true;
  rigidTime = time;
  const std::vector<glm::dmat4> poses = rigidObjectTransforms(scene, time);
  for (size_t i = 0; i < poses.size(); ++i) {
    const uint32_t id = scene.rigidObjects[i].object;
    if (!rigidObject[id] || poses[i] == objects[id].transform) continue;
    const glm::dmat4& m = poses[i];
    bool finite = true;
    for (int c = 0; c < 4; ++c)
      for (int k = 0; k < 4; ++k) finite = finite && std::isfinite(m[c][k]);
    const double det = glm::determinant(glm::dmat3(m));
    if (!finite || !(std::abs(det) >= 1e-30) || !std::isfinite(det)) continue;
    Object moved = objects[id];
    moved.transform = m;
    const uint32_t list = gpu::objectDrawList(packObject(moved, scene).flags);
    const uint32_t from = gpuScene.objectList[id];
    if (list != from) {
      if (list != DRAW_LIST_NONE && (swListMask >> list & 1u) && listLive[list] >= listObjectCapacity(list)) continue;
      if (from != DRAW_LIST_NONE) --listLive[from];
      if (list != DRAW_LIST_NONE) ++listLive[list];
      gpuScene.objectList[id] = list;
    }
    objects[id].transform = m;
    markDirty(id);
  }
}

uint32_t Renderer::objectSlots() const { return uint32_t(impl_->slotState.size()); }

const Object* Renderer::object(uint32_t id) const {
  return impl_->isLive(id) ? &impl_->objects[id] : nullptr;
}

void Renderer::Impl::recordObjectUploads(VkCommandBuffer cmd, FrameSlot& slot, FrameStats& st) {
  if (dirty.empty()) return;
  // The slot's staging buffer: the records, then their object IDs; one scatter dispatch writes them into place
  // (a copy command would need one region per run of consecutive IDs: thousands for scattered changes).
  const uint32_t count = uint32_t(dirty.size());
  constexpr VkDeviceSize kRecord = sizeof(gpu::ObjectData);
  const VkDeviceSize idsOffset = VkDeviceSize(count) * kRecord, bytes = idsOffset + VkDeviceSize(count) * 4;
  if (slot.staging.size() < bytes)
    slot.staging = gpu::Buffer(device, std::max<VkDeviceSize>(bytes, 2 * slot.staging.size()),
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                               gpu::MemoryUse::HostVisible);
  auto* base = static_cast<uint8_t*>(slot.staging.mapped());
  auto* records = reinterpret_cast<gpu::ObjectData*>(base);
  auto* ids = reinterpret_cast<uint32_t*>(base + idsOffset);
  std::memcpy(records, dirtyRecords.data(), size_t(count) * sizeof(gpu::ObjectData));
  std::memcpy(ids, dirty.data(), size_t(count) * sizeof(uint32_t));
  for (uint32_t id : dirty) dirtyIndex[id] = 0;
  objectUpload.record(cmd, slot.staging, idsOffset, gpuScene.objects, count);  // (the frame graph orders it)
  st.upload.objects = count;
  st.upload.bytes = bytes;
  dirty.clear();
  dirtyRecords.clear();
}

}  // namespace visbuf
