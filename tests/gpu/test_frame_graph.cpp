// The frame graph: which passes it keeps, which barriers and layout transitions it derives, and the frames the
// renderer declares through it (what a frame does not need is dropped; what it needs is never dropped).
#include <algorithm>
#include <array>

#include "gpu_test_util.h"
#include "visbuf/gpu/check.h"
#include "visbuf/gpu/frame_graph.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/light.h"

using namespace visbuf;
using gpu::FrameGraph;
namespace ga = gpu::access;  // (POSIX has an access() at global scope)

namespace {

// Command buffers of the test device's pool, freed with the fixture.
struct Commands {
  gpu::Device& dev;
  std::array<VkCommandBuffer, 8> cmds{};
  explicit Commands(gpu::Device& d) : dev(d) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = dev.commandPool();
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = uint32_t(cmds.size());
    VK_CHECK(vkAllocateCommandBuffers(dev.device(), &ai, cmds.data()));
  }
  ~Commands() { vkFreeCommandBuffers(dev.device(), dev.commandPool(), uint32_t(cmds.size()), cmds.data()); }
  static void begin(VkCommandBuffer cmd) {
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd, &bi));
  }
  void submit(size_t count) {
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = uint32_t(count);
    si.pCommandBuffers = cmds.data();
    VK_CHECK(vkQueueSubmit(dev.queue(), 1, &si, VK_NULL_HANDLE));
    VK_CHECK(vkQueueWaitIdle(dev.queue()));
  }
};

}  // namespace

// A buffer written by a fill and read by a copy, an image cleared and copied out, and a pass whose write nothing
// reads: the unread pass is dropped, the others get exactly the dependencies their uses need, and the copies see
// what was written.
TEST(FrameGraph, DropsUnreadPassesAndDerivesTheBarriersTheUsesNeed) {
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  gpu::Buffer src(dev, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                  gpu::MemoryUse::DeviceLocal);
  gpu::Buffer unread(dev, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::DeviceLocal);
  gpu::Buffer out(dev, 256 + 16 * 16 * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  gpu::Image image(dev, VK_FORMAT_R32_UINT, 16, 16,
                   VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_STORAGE_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT);
  Commands c(dev);

  FrameGraph g;
  const FrameGraph::Resource a = g.buffer("a"), b = g.buffer("b"), img = g.image("image", image);
  const FrameGraph::Resource host = g.buffer("host copy");
  bool unreadRan = false;
  g.pass("fill").step({FrameGraph::overwrites(a, ga::transferWrite)},
                      [&](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, src.handle(), 0, 256, 0x01020304u); });
  g.pass("unread").step({FrameGraph::overwrites(b, ga::transferWrite)}, [&](VkCommandBuffer cmd) {
    unreadRan = true;
    vkCmdFillBuffer(cmd, unread.handle(), 0, 256, 0);
  });
  g.pass("clear").step({FrameGraph::overwrites(img, ga::transferWrite)}, [&](VkCommandBuffer cmd) {
    VkClearColorValue v{};
    v.uint32[0] = 7u;
    VkImageSubresourceRange range{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &v, 1, &range);
  });
  g.pass("copy out")
      .sideEffect()
      .step({FrameGraph::reads(a, ga::transferRead), FrameGraph::reads(img, ga::transferRead),
             FrameGraph::overwrites(host, ga::transferWrite)},
            [&](VkCommandBuffer cmd) {
              VkBufferCopy bc{0, 0, 256};
              vkCmdCopyBuffer(cmd, src.handle(), out.handle(), 1, &bc);
              VkBufferImageCopy region{};
              region.bufferOffset = 256;
              region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
              region.imageExtent = {16, 16, 1};
              vkCmdCopyImageToBuffer(cmd, image.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, out.handle(), 1, &region);
            });
  const FrameGraph::Report report = g.record(c.cmds, Commands::begin, nullptr);
  EXPECT_EQ(report.recorded, (std::vector<std::string>{"fill", "clear", "copy out"}));
  EXPECT_EQ(report.dropped, (std::vector<std::string>{"unread"}));
  EXPECT_FALSE(unreadRan) << "a dropped pass records nothing";
  // The frame boundary; "clear": UNDEFINED -> TRANSFER_DST; "copy out": one barrier with the buffer's write->read
  // dependency and TRANSFER_DST -> TRANSFER_SRC.
  EXPECT_EQ(report.barriers, 3u);
  EXPECT_EQ(report.layoutTransitions, 2u);
  c.submit(report.recorded.size());
  const auto* words = static_cast<const uint32_t*>(out.mapped());
  for (int i = 0; i < 64; ++i) ASSERT_EQ(words[i], 0x01020304u) << i;
  for (int i = 0; i < 256; ++i) ASSERT_EQ(words[64 + i], 7u) << i;
  EXPECT_NO_VALIDATION_MESSAGES(before);
}

// A read already made visible needs no second barrier; a write after reads waits for them; an image kept from
// frame to frame is returned to its layout; an output is left in the layout asked for.
TEST(FrameGraph, ReadsShareOneBarrierAndKeptLayoutsAreRestored) {
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  gpu::Buffer buf(dev, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                  gpu::MemoryUse::DeviceLocal);
  gpu::Buffer out(dev, 256, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  gpu::Image kept(dev, VK_FORMAT_R32_UINT, 8, 8, VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                                                     VK_IMAGE_USAGE_STORAGE_BIT,
                  VK_IMAGE_ASPECT_COLOR_BIT);
  {  // kept in GENERAL between frames
    VkCommandBuffer one = dev.beginOneShot();
    gpu::imageBarrier(one, kept, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_2_NONE, 0,
                      VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0);
    dev.submitOneShot(one);
  }
  Commands c(dev);
  for (int frame = 0; frame < 2; ++frame) {
    FrameGraph g;
    const FrameGraph::Resource b = g.buffer("b"), k = g.image("kept", kept, VK_IMAGE_LAYOUT_GENERAL);
    auto copy = [&](VkCommandBuffer cmd) {
      VkBufferCopy bc{0, 0, 256};
      vkCmdCopyBuffer(cmd, buf.handle(), out.handle(), 1, &bc);
    };
    g.pass("write").step({FrameGraph::overwrites(b, ga::transferWrite)},
                         [&](VkCommandBuffer cmd) { vkCmdFillBuffer(cmd, buf.handle(), 0, 256, 5u); });
    g.pass("read 1").sideEffect().step({FrameGraph::reads(b, ga::transferRead)}, copy);
    g.pass("read 2").sideEffect().step({FrameGraph::reads(b, ga::transferRead)}, copy);
    g.pass("write again").sideEffect().step({FrameGraph::writes(b, ga::transferWrite),
                                             FrameGraph::reads(k, ga::transferRead)},
                                            [&](VkCommandBuffer cmd) {
                                              vkCmdFillBuffer(cmd, buf.handle(), 0, 256, 6u);
                                              VkBufferImageCopy region{};
                                              region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
                                              region.imageExtent = {8, 8, 1};
                                              vkCmdCopyImageToBuffer(cmd, kept.handle(),
                                                                     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                                                     out.handle(), 1, &region);
                                            });
    const FrameGraph::Report report = g.record(c.cmds, Commands::begin, nullptr);
    EXPECT_EQ(report.recorded.size(), 4u);
    // Boundary; read 1 (write -> read); read 2: none (already visible); write again: after the reads, with
    // GENERAL -> TRANSFER_SRC; end: TRANSFER_SRC -> GENERAL for the next frame.
    EXPECT_EQ(report.barriers, 4u) << "frame " << frame;
    EXPECT_EQ(report.layoutTransitions, 2u);
    c.submit(report.recorded.size());
  }
  EXPECT_NO_VALIDATION_MESSAGES(before);
}

// The renderer's frames through the graph: a pyramid the plan skips and light lists the shading does not read are
// dropped by the structure, not by a flag in the pass; the passes a frame needs are recorded in order.
TEST(FrameGraph, RendererDropsThePassesAFrameDoesNotRead) {
  gpu::Device& dev = test::testDevice();
  const uint32_t before = dev.validationMessages();
  FieldParams p;
  p.objects = 300;
  p.extent = 30.0;
  Scene scene = makeFieldScene(p).value();
  scatterPointLights(scene, 20, 2);
  auto renderer = Renderer::create(dev, scene, {.width = 160, .height = 120});
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  Camera cam;
  cam.position = {0.0, 5.0, 60.0};
  cam.target = {0.0, 0.0, 0.0};
  auto contains = [](const std::vector<std::string>& v, const char* s) {
    return std::find(v.begin(), v.end(), s) != v.end();
  };

  FrameOptions fo;
  fo.cull = CullMode::Occlusion;
  fo.readPyramid = true;  // (built every frame while it is read back)
  auto tiled = (*renderer)->renderFrame(cam, fo);
  ASSERT_TRUE(tiled.ok());
  EXPECT_TRUE(contains(tiled->stats.graph.passesRecorded, "depth pyramid"));
  EXPECT_TRUE(contains(tiled->stats.graph.passesRecorded, "light cull"));
  EXPECT_TRUE(tiled->stats.graph.passesDropped.empty());
  EXPECT_EQ(tiled->stats.graph.passesRecorded.front(), "setup");
  EXPECT_GT(tiled->stats.graph.barriers, tiled->stats.graph.passesRecorded.size() / 2);

  fo.tiledLights = false;
  fo.readPyramid = false;
  fo.skipUselessPyramid = true;
  // Frames until the pyramid is skipped: from above the field nothing is occluded, so the plan stops building it.
  Result<FrameResult> f = (*renderer)->renderFrame(cam, fo);
  for (int i = 0; i < 4 && f.ok() && !f->stats.pyramid.skipped; ++i) f = (*renderer)->renderFrame(cam, fo);
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(f->stats.pyramid.skipped);
  EXPECT_TRUE(contains(f->stats.graph.passesDropped, "depth pyramid"));
  EXPECT_TRUE(contains(f->stats.graph.passesDropped, "light cull"));
  EXPECT_FALSE(contains(f->stats.graph.passesRecorded, "light cull"));
  EXPECT_TRUE(contains(f->stats.graph.passesRecorded, "shade")) << "the frame's colour is its product, read back or not";
  // The skipped passes took no GPU time.
  for (const auto& [name, ms] : f->stats.graph.passMs) EXPECT_NE(name, "depth pyramid");
  EXPECT_NO_VALIDATION_MESSAGES(before);
}
