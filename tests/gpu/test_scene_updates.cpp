// Scenes that change every frame, and frames the host records with several in flight:
// - occlusion culling stays conservative while objects move, appear, disappear and hide (ID image equal to no
//   culling every frame);
// - record() with three frames in flight gives, frame for frame, the image renderFrame gives;
// - the update API refuses bad changes whole and uploads only what changed;
// - glTF node animation poses objects through the same path.
#include <cstring>
#include <filesystem>
#include <set>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include "../unit/test_assets.h"
#include "gpu_test_util.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/render/scene_motion.h"
#include "visbuf/scene/gpu_scene.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

Scene cityScene(uint32_t objects) {
  CityParams p;
  p.objects = objects;
  p.seed = 11;
  return makeCityScene(p).value();
}

Scene fieldScene(uint32_t objects) {
  FieldParams p;
  p.objects = objects;
  p.seed = 7;
  p.extent = 60.0;
  p.mesh = makeTorusKnot(48, 12);
  return makeFieldScene(p).value();
}

// A street-level walk through the city: forward, turning, and one cut.
Camera walk(const Scene& scene, int frame, int frames) {
  const double t = double(frame) / frames;
  Camera c = scene.defaultCamera;
  c.position += glm::dvec3(6.0 * std::sin(t * 9.0), 0.4 * std::sin(t * 5.0), -t * 120.0);
  if (frame >= frames / 2) c.position += glm::dvec3(25.0, 8.0, 0.0);
  const double yaw = std::sin(t * 11.0) * 1.3;
  c.target = c.position + glm::dvec3(std::sin(yaw), -0.08, -std::cos(yaw));
  return c;
}

FrameOptions idFrame(CullMode cull) {
  FrameOptions fo;
  fo.cull = cull;
  fo.readColor = false;
  fo.readIds = true;
  // LOD on: each object's level depends on the camera alone, so both renderers draw the same triangles (with LOD
  // off, the unculled reference draws 110M triangles a frame).
  return fo;
}

}  // namespace

// The test: a 100-frame path at 100k objects, 10 % of them moving every frame, 100 removed, 100 added and
// 100 hidden every frame (shown again 3 frames later). Two renderers receive the same changes; the one culling
// with the depth pyramid must give the ID image of the one that culls nothing, every frame.
GPU_TEST(SceneUpdates, MovingObjectsOcclusionEqualsNoCulling) {
  const Scene scene = cityScene(100000);
  const SceneMotionParams mp{.moving = 0.1, .churn = 0.001, .seed = 3};
  auto motionA = SceneMotion::create(scene, mp), motionB = SceneMotion::create(scene, mp);
  ASSERT_TRUE(motionA.ok() && motionB.ok());
  const RendererConfig rc{.width = 160, .height = 96, .spareObjects = motionA->spareObjects()};
  auto culled = Renderer::create(dev, scene, rc), reference = Renderer::create(dev, scene, rc);
  ASSERT_TRUE(culled.ok() && reference.ok()) << (culled.ok() ? reference.error().message : culled.error().message);
  const FrameOptions on = idFrame(CullMode::Occlusion), off = idFrame(CullMode::None);
  const int frames = 100;
  uint64_t occluded = 0, covered = 0, uploaded = 0;
  uint32_t moved = 0, added = 0, removed = 0, hidden = 0, lateDraws = 0;
  for (int i = 0; i < frames; ++i) {
    auto ca = motionA->apply(**culled, uint32_t(i));
    auto cb = motionB->apply(**reference, uint32_t(i));
    ASSERT_TRUE(ca.ok() && cb.ok()) << (ca.ok() ? cb.error().message : ca.error().message);
    moved += ca->moved;
    added += ca->added;
    removed += ca->removed;
    hidden += ca->hidden;
    const Camera cam = walk(scene, i, frames);
    auto a = (*culled)->renderFrame(cam, on);
    auto b = (*reference)->renderFrame(cam, off);
    ASSERT_TRUE(a.ok() && b.ok());
    occluded += a->stats.cull.occlusionCulled;
    lateDraws += a->stats.cull.drawsLate;
    uploaded += a->stats.upload.bytes;
    EXPECT_EQ(a->stats.upload.bytes, b->stats.upload.bytes);
    size_t mismatches = 0;
    std::set<std::pair<uint32_t, uint32_t>> wrong;  // (object + 1 culled, object + 1 reference)
    for (size_t p = 0; p < a->ids.size(); p += 2) {
      if (a->ids[p] != b->ids[p] || a->ids[p + 1] != b->ids[p + 1]) {
        ++mismatches;
        wrong.insert({a->ids[p], b->ids[p]});
      }
      covered += a->ids[p] != 0;
    }
    std::string which;
    for (const auto& [x, y] : wrong) which += " " + std::to_string(int64_t(x) - 1) + "/" + std::to_string(int64_t(y) - 1);
    ASSERT_EQ(mismatches, 0u) << "frame " << i << ": occlusion culling changed " << mismatches
                              << " pixels (object culled/reference:" << which << ")";
  }
  std::printf("%d frames, %zu objects: %u moves, %u added, %u removed, %u hidden; %llu bytes uploaded "
              "(%.1f KiB a frame); %llu occlusion-culled, %u late draws, %llu covered pixels, IDs identical\n",
              frames, scene.objects.size(), moved, added, removed, hidden, (unsigned long long)uploaded,
              double(uploaded) / frames / 1024.0, (unsigned long long)occluded, lateDraws,
              (unsigned long long)covered);
  EXPECT_GT(occluded, 0u) << "the path must exercise occlusion culling";
  EXPECT_GT(covered, 0u);
  EXPECT_EQ(added, uint32_t(frames) * 100u);
  EXPECT_EQ(removed, uint32_t(frames) * 100u);
}

// record() with three frames in flight, the host submitting each frame with its own copy of the colour output
// and waiting only on the ring's fences; the scene changing every frame. Frame n's colour equals renderFrame's of
// the same camera and the same changes (a second renderer), and completedStats() reports frame n - 3.
GPU_TEST(SceneUpdates, RecordThreeInFlightMatchesRenderFrame) {
  const Scene scene = fieldScene(3000);
  const SceneMotionParams mp{.moving = 0.3, .churn = 0.01, .seed = 5};
  auto motionA = SceneMotion::create(scene, mp), motionB = SceneMotion::create(scene, mp);
  ASSERT_TRUE(motionA.ok() && motionB.ok());
  const uint32_t w = 192, h = 128, inFlight = 3;
  auto ring = Renderer::create(dev, scene,
                               {.width = w, .height = h, .framesInFlight = inFlight,
                                .spareObjects = motionA->spareObjects()});
  auto single = Renderer::create(dev, scene, {.width = w, .height = h, .spareObjects = motionB->spareObjects()});
  ASSERT_TRUE(ring.ok() && single.ok());

  VkDevice vk = dev.device();
  struct Slot {
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    VkFence fence = VK_NULL_HANDLE;
    gpu::Buffer readback;
    int frame = -1;
  };
  std::vector<Slot> slots(inFlight);
  for (Slot& s : slots) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = dev.commandPool();
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    ASSERT_EQ(vkAllocateCommandBuffers(vk, &ai, &s.cmd), VK_SUCCESS);
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    ASSERT_EQ(vkCreateFence(vk, &fi, nullptr, &s.fence), VK_SUCCESS);
    s.readback = gpu::Buffer(dev, VkDeviceSize(w) * h * 8, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  }
  std::vector<Camera> cameras;
  std::vector<std::vector<float>> expected;
  int compared = 0;
  double worst = 0.0;
  // Waits for slot s's frame and compares its colour with renderFrame's.
  auto check = [&](Slot& s) {
    ASSERT_EQ(vkWaitForFences(vk, 1, &s.fence, VK_TRUE, UINT64_MAX), VK_SUCCESS);
    if (s.frame < 0) return;
    const auto* half = static_cast<const uint16_t*>(s.readback.mapped());
    const std::vector<float>& ref = expected[size_t(s.frame)];
    double maxDiff = 0.0;
    for (size_t i = 0; i < ref.size(); ++i)
      maxDiff = std::max(maxDiff, double(std::abs(glm::unpackHalf1x16(half[i]) - ref[i])));
    worst = std::max(worst, maxDiff);
    EXPECT_EQ(maxDiff, 0.0) << "frame " << s.frame << ": record() and renderFrame differ";
    ++compared;
    s.frame = -1;
  };
  const int frames = 12;
  FrameOptions fo;
  fo.readColor = false;
  for (int n = 0; n < frames; ++n) {
    Camera cam = scene.defaultCamera;
    const double a = 0.25 * n;
    cam.position = glm::dvec3(150.0 * std::sin(a), 30.0, 150.0 * std::cos(a));
    cam.target = glm::dvec3(0.0);
    // The reference: the same changes, then a synchronous frame.
    ASSERT_TRUE(motionB->apply(**single, uint32_t(n)).ok());
    FrameOptions ro = fo;
    ro.readColor = true;
    auto ref = (*single)->renderFrame(cam, ro);
    ASSERT_TRUE(ref.ok()) << ref.error().message;
    expected.push_back(ref->color);

    Slot& s = slots[size_t(n) % inFlight];
    check(s);  // the ring: frame n - 3 must be done before its slot is reused
    ASSERT_TRUE(motionA->apply(**ring, uint32_t(n)).ok());
    auto frame = (*ring)->record({cam, fo, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL});
    ASSERT_TRUE(frame.ok()) << frame.error().message;
    EXPECT_EQ(frame->index, uint64_t(n));
    if (n >= int(inFlight)) {
      ASSERT_TRUE((*ring)->completedStats().has_value());
      EXPECT_EQ((*ring)->completedStats()->frameIndex, uint64_t(n - int(inFlight)));
    }
    ASSERT_EQ(vkResetCommandBuffer(s.cmd, 0), VK_SUCCESS);
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    ASSERT_EQ(vkBeginCommandBuffer(s.cmd, &bi), VK_SUCCESS);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {frame->width, frame->height, 1};
    vkCmdCopyImageToBuffer(s.cmd, frame->color.image, frame->color.layout, s.readback.handle(), 1, &region);
    gpu::memoryBarrier(s.cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
    ASSERT_EQ(vkEndCommandBuffer(s.cmd), VK_SUCCESS);
    std::vector<VkCommandBufferSubmitInfo> cmds;
    for (VkCommandBuffer c : frame->commandBuffers)
      cmds.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, c, 0});
    cmds.push_back({VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO, nullptr, s.cmd, 0});
    VkSubmitInfo2 submit{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
    submit.commandBufferInfoCount = uint32_t(cmds.size());
    submit.pCommandBufferInfos = cmds.data();
    ASSERT_EQ(vkResetFences(vk, 1, &s.fence), VK_SUCCESS);
    ASSERT_EQ(vkQueueSubmit2(dev.queue(), 1, &submit, s.fence), VK_SUCCESS);
    s.frame = n;
  }
  for (Slot& s : slots) check(s);
  for (Slot& s : slots) {
    vkDestroyFence(vk, s.fence, nullptr);
    vkFreeCommandBuffers(vk, dev.commandPool(), 1, &s.cmd);
  }
  std::printf("%d frames recorded with %u in flight: every colour image identical to renderFrame's (max %.3g)\n",
              compared, inFlight, worst);
  EXPECT_EQ(compared, frames);
}

// Bad changes are refused whole, with the object named; only changed records are uploaded.
GPU_TEST(SceneUpdates, RefusalsAndUploadedBytes) {
  const Scene scene = fieldScene(200);
  auto r = Renderer::create(dev, scene, {.width = 64, .height = 64, .spareObjects = 2});
  ASSERT_TRUE(r.ok());
  Renderer& R = **r;
  FrameOptions fo;
  fo.readColor = false;
  auto f = R.renderFrame(scene.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->stats.upload.bytes, 0u) << "a frame without changes uploads nothing";
  EXPECT_EQ(R.objectSlots(), 202u);

  const glm::dmat4 moved = glm::translate(scene.objects[3].transform, glm::dvec3(1.0, 0.0, 0.0));
  glm::dmat4 nan = moved;
  nan[3][1] = std::nan("");
  const ObjectTransform bad[] = {{3, moved}, {7, nan}};
  Status s = R.setTransforms(bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("object 7"), std::string::npos) << s.error().message;
  EXPECT_EQ(R.object(3)->transform, scene.objects[3].transform) << "a refused batch applies nothing";
  EXPECT_FALSE(R.setTransforms(std::vector<ObjectTransform>{{3, glm::dmat4(0.0)}}).ok()) << "singular";
  EXPECT_FALSE(R.setTransforms(std::vector<ObjectTransform>{{200, moved}}).ok()) << "a free slot";
  EXPECT_FALSE(R.setVisible(500, false).ok());
  EXPECT_FALSE(R.removeObject(201).ok());
  EXPECT_FALSE(R.addObject({moved, 99, 0}).ok()) << "no such mesh";

  ASSERT_TRUE(R.setTransforms(std::vector<ObjectTransform>{{3, moved}, {4, moved}}).ok());
  ASSERT_TRUE(R.setVisible(10, false).ok());
  ASSERT_TRUE(R.removeObject(11).ok());
  auto a = R.addObject({moved, 0, 0});
  auto b = R.addObject({moved, 0, 0});
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(*a, 11u) << "the lowest free slot is reused first";
  EXPECT_EQ(*b, 200u);
  auto c = R.addObject({moved, 0, 0});
  ASSERT_TRUE(c.ok()) << c.error().message;
  auto d = R.addObject({moved, 0, 0});
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.error().code, ErrorCode::CapacityExceeded);
  f = R.renderFrame(scene.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  // Objects 3, 4, 10, 11, 200, 201: six records and their IDs.
  EXPECT_EQ(f->stats.upload.objects, 6u);
  EXPECT_EQ(f->stats.upload.bytes, 6u * (sizeof(gpu::ObjectData) + sizeof(uint32_t)));
  f = R.renderFrame(scene.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->stats.upload.bytes, 0u);
}

// glTF node animation goes through the scene-update path: CesiumMilkTruck at t = 0.4 s (its two wheels turned)
// renders exactly as a static copy of the scene whose wheel objects hold rigidObjectTransform(t) (the CPU's
// double-precision pose), and a frame at a new time uploads the two wheel records only.
GPU_TEST(SceneUpdates, RigidAnimationEqualsTheSamePoseAsStaticTransforms) {
  const std::filesystem::path file =
      std::filesystem::path(VISBUF_ASSETS_DIR) / "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb";
  REQUIRE_ASSET(file);
  GltfImportReport report;
  auto imported = importGltfScene(file.string(), {}, &report);
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  auto scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->rigidObjects.size(), 2u) << "the truck's two wheel nodes";
  const double t = 0.4;
  Scene posed = *scene;
  const std::vector<glm::dmat4> poses = rigidObjectTransforms(*scene, t);
  for (size_t i = 0; i < poses.size(); ++i) posed.objects[scene->rigidObjects[i].object].transform = poses[i];
  posed.rigidObjects.clear();

  Camera side = scene->defaultCamera;  // from the side: the wheels face the camera
  const double distance = glm::length(side.position - side.target);
  side.position = side.target + glm::dvec3(distance, 0.15 * distance, 0.0);
  const RendererConfig rc{.width = 200, .height = 150};
  auto animated = Renderer::create(dev, *scene, rc), still = Renderer::create(dev, posed, rc);
  ASSERT_TRUE(animated.ok() && still.ok());
  FrameOptions fo;
  fo.readIds = true;
  fo.lodErrorPixels = 0.0f;
  auto start = (*animated)->renderFrame(side, fo);
  ASSERT_TRUE(start.ok());
  fo.animationTime = t;
  auto a = (*animated)->renderFrame(side, fo);
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(a->stats.upload.objects, 2u) << "the two wheels";
  EXPECT_EQ(a->stats.upload.bytes, 2u * (sizeof(gpu::ObjectData) + sizeof(uint32_t)));
  auto again = (*animated)->renderFrame(side, fo);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->stats.upload.bytes, 0u) << "the same time again: nothing changed";
  fo.animationTime = 0.0;
  auto b = (*still)->renderFrame(side, fo);
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(a->ids, b->ids);
  const ImageError same = compareColor(a->color, b->color);
  EXPECT_EQ(same.maxAbs, 0.0) << "the animated and the static wheels differ";
  const ImageError turned = compareColor(a->color, start->color);
  EXPECT_GT(turned.differingFraction, 0.0) << "the wheels did not turn between t = 0 and t = " << t;
  std::printf("CesiumMilkTruck t=%.1f: identical to the static pose (max %.3g); %.2f%% of pixels differ from t=0\n",
              t, same.maxAbs, 100.0 * turned.differingFraction);
  test::saveOnFailure("rigid_truck", *a, *b);
}
