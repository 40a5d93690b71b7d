// The frame graph: which passes it keeps, which barriers and layout transitions it derives, and the frames the
// renderer declares through it (what a frame does not need is dropped; what it needs is never dropped).
#include <dlfcn.h>

#include <algorithm>
#include <array>
#include <vector>

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

// The barriers recorded while `captured` is set: each vkCmdPipelineBarrier2 with its command buffer and its memory and
// image barriers (the graph records no buffer barriers: buffers are synchronised by its global memory barrier).
struct RecordedBarrier {
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  std::vector<VkMemoryBarrier2> memory;
  std::vector<VkImageMemoryBarrier2> images;
  uint32_t bufferBarriers = 0;
};
std::vector<RecordedBarrier>* captured = nullptr;

}  // namespace

// This executable's vkCmdPipelineBarrier2: the engine is linked in from static libraries, so every barrier it records
// comes here (a definition in the executable takes precedence over the Vulkan loader's) and goes on to the loader's,
// found with dlsym(RTLD_NEXT). The validation layers see every call as before; a test reads what was recorded.
extern "C" VKAPI_ATTR void VKAPI_CALL vkCmdPipelineBarrier2(VkCommandBuffer cmd, const VkDependencyInfo* info) {
  static const auto next = reinterpret_cast<PFN_vkCmdPipelineBarrier2>(dlsym(RTLD_NEXT, "vkCmdPipelineBarrier2"));
  if (!next) {
    std::fprintf(stderr, "test_frame_graph: the Vulkan loader's vkCmdPipelineBarrier2 was not found\n");
    std::abort();
  }
  if (captured) {
    RecordedBarrier r;
    r.cmd = cmd;
    r.memory.assign(info->pMemoryBarriers, info->pMemoryBarriers + info->memoryBarrierCount);
    r.images.assign(info->pImageMemoryBarriers, info->pImageMemoryBarriers + info->imageMemoryBarrierCount);
    r.bufferBarriers = info->bufferMemoryBarrierCount;
    captured->push_back(std::move(r));
  }
  next(cmd, info);
}

namespace {

// Records into `barriers` while it lives.
struct CaptureBarriers {
  explicit CaptureBarriers(std::vector<RecordedBarrier>& barriers) { captured = &barriers; }
  ~CaptureBarriers() { captured = nullptr; }
};

// A barrier as the test derives it by hand: one global memory barrier (or none) and the image layout transitions,
// each on a whole single-level, single-layer colour image.
struct Memory {
  VkPipelineStageFlags2 srcStages;
  VkAccessFlags2 srcAccess;
  VkPipelineStageFlags2 dstStages;
  VkAccessFlags2 dstAccess;
};
struct Transition {
  const char* image;  // (for messages)
  VkImage handle;
  VkPipelineStageFlags2 srcStages;
  VkAccessFlags2 srcAccess;
  VkPipelineStageFlags2 dstStages;
  VkAccessFlags2 dstAccess;
  VkImageLayout oldLayout, newLayout;
};
struct Expected {
  size_t cmd;  // index into the command buffers
  std::vector<Memory> memory;
  std::vector<Transition> images;
};

// The frame boundary every graph records first: whatever ran before is done and its writes visible to everything.
const Memory kBoundary{VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                       VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                       VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT};

void expectBarriers(const std::vector<RecordedBarrier>& got, const std::vector<Expected>& want,
                    const std::array<VkCommandBuffer, 8>& cmds) {
  ASSERT_EQ(got.size(), want.size()) << "pipeline barriers recorded";
  for (size_t i = 0; i < want.size(); ++i) {
    SCOPED_TRACE("barrier " + std::to_string(i));
    const RecordedBarrier& g = got[i];
    const Expected& w = want[i];
    EXPECT_EQ(g.cmd, cmds[w.cmd]) << "recorded into command buffer " << w.cmd;
    EXPECT_EQ(g.bufferBarriers, 0u);
    ASSERT_EQ(g.memory.size(), w.memory.size()) << "global memory barriers";
    for (size_t m = 0; m < w.memory.size(); ++m) {
      EXPECT_EQ(g.memory[m].srcStageMask, w.memory[m].srcStages) << "memory: source stages";
      EXPECT_EQ(g.memory[m].srcAccessMask, w.memory[m].srcAccess) << "memory: source access";
      EXPECT_EQ(g.memory[m].dstStageMask, w.memory[m].dstStages) << "memory: destination stages";
      EXPECT_EQ(g.memory[m].dstAccessMask, w.memory[m].dstAccess) << "memory: destination access";
    }
    ASSERT_EQ(g.images.size(), w.images.size()) << "image layout transitions";
    for (size_t k = 0; k < w.images.size(); ++k) {
      const VkImageMemoryBarrier2& b = g.images[k];
      const Transition& t = w.images[k];
      SCOPED_TRACE(t.image);
      EXPECT_EQ(b.image, t.handle) << "the transition's image";
      EXPECT_EQ(b.srcStageMask, t.srcStages) << "source stages";
      EXPECT_EQ(b.srcAccessMask, t.srcAccess) << "source access";
      EXPECT_EQ(b.dstStageMask, t.dstStages) << "destination stages";
      EXPECT_EQ(b.dstAccessMask, t.dstAccess) << "destination access";
      EXPECT_EQ(b.oldLayout, t.oldLayout);
      EXPECT_EQ(b.newLayout, t.newLayout);
      EXPECT_EQ(b.srcQueueFamilyIndex, VK_QUEUE_FAMILY_IGNORED);
      EXPECT_EQ(b.dstQueueFamilyIndex, VK_QUEUE_FAMILY_IGNORED);
      EXPECT_EQ(b.subresourceRange.aspectMask, VkImageAspectFlags(VK_IMAGE_ASPECT_COLOR_BIT));
      EXPECT_EQ(b.subresourceRange.baseMipLevel, 0u);
      EXPECT_EQ(b.subresourceRange.levelCount, 1u);
      EXPECT_EQ(b.subresourceRange.baseArrayLayer, 0u);
      EXPECT_EQ(b.subresourceRange.layerCount, 1u);
    }
  }
}

constexpr VkPipelineStageFlags2 kTransfer = VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT;
constexpr VkPipelineStageFlags2 kCompute = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;

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
GPU_TEST(FrameGraph, DropsUnreadPassesAndDerivesTheBarriersTheUsesNeed) {
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
  std::vector<RecordedBarrier> barriers;
  FrameGraph::Report report;
  {
    const CaptureBarriers capture(barriers);
    report = g.record(c.cmds, Commands::begin, nullptr);
  }
  EXPECT_EQ(report.recorded, (std::vector<std::string>{"fill", "clear", "copy out"}));
  EXPECT_EQ(report.dropped, (std::vector<std::string>{"unread"}));
  EXPECT_FALSE(unreadRan) << "a dropped pass records nothing";
  // By hand, pass by pass (a resource not yet written or read this frame needs no dependency):
  //   "fill" (cmd 0): the frame boundary; `a` overwritten with nothing before it: no barrier.
  //   "clear" (cmd 1): the image overwritten (its old content discarded: UNDEFINED), nothing before it: a transition
  //     from no stage to the transfer write, UNDEFINED -> TRANSFER_DST.
  //   "copy out" (cmd 2): `a` read after fill's transfer write: a global transfer write -> transfer read; the image
  //     read after clear's transfer write in another layout: transfer write -> transfer read, TRANSFER_DST ->
  //     TRANSFER_SRC; `host` overwritten with nothing before it: nothing. One pipeline barrier for both.
  //   No outputs and no kept layouts: nothing at the end.
  expectBarriers(barriers,
                 {{0, {kBoundary}, {}},
                  {1,
                   {},
                   {{"image", image.handle(), VK_PIPELINE_STAGE_2_NONE, 0, kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                     VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL}}},
                  {2,
                   {{kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kTransfer, VK_ACCESS_2_TRANSFER_READ_BIT}},
                   {{"image", image.handle(), kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kTransfer,
                     VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL}}}},
                 c.cmds);
  EXPECT_EQ(report.barriers, 3u);
  EXPECT_EQ(report.layoutTransitions, 2u);
  c.submit(report.recorded.size());
  const auto* words = static_cast<const uint32_t*>(out.mapped());
  for (int i = 0; i < 64; ++i) ASSERT_EQ(words[i], 0x01020304u) << i;
  for (int i = 0; i < 256; ++i) ASSERT_EQ(words[64 + i], 7u) << i;
}

// A read already made visible needs no second barrier; a write after reads waits for them; an image kept from
// frame to frame is returned to its layout; an output is left in the layout asked for.
GPU_TEST(FrameGraph, ReadsShareOneBarrierAndKeptLayoutsAreRestored) {
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
    std::vector<RecordedBarrier> barriers;
    FrameGraph::Report report;
    {
      const CaptureBarriers capture(barriers);
      report = g.record(c.cmds, Commands::begin, nullptr);
    }
    EXPECT_EQ(report.recorded.size(), 4u);
    SCOPED_TRACE("frame " + std::to_string(frame));
    // By hand:
    //   "write" (cmd 0): the frame boundary; `b` overwritten with nothing before it: no barrier.
    //   "read 1" (cmd 1): `b` read after the transfer write: a global transfer write -> transfer read.
    //   "read 2" (cmd 2): the same read, already made visible: no barrier.
    //   "write again" (cmd 3): `b` written after the write and the reads: a global barrier from the transfer stage
    //     (the reads' stage, the write's access) to the transfer write; the kept image read in TRANSFER_SRC, which
    //     starts the frame in GENERAL untouched: from no stage, GENERAL -> TRANSFER_SRC. One pipeline barrier.
    //     At the end of the frame (the last pass): the kept image back to GENERAL after the transfer read (an
    //     execution dependency only: a read has nothing to make available), for any later command.
    expectBarriers(barriers,
                   {{0, {kBoundary}, {}},
                    {1, {{kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kTransfer, VK_ACCESS_2_TRANSFER_READ_BIT}}, {}},
                    {3,
                     {{kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT, kTransfer, VK_ACCESS_2_TRANSFER_WRITE_BIT}},
                     {{"kept", kept.handle(), VK_PIPELINE_STAGE_2_NONE, 0, kTransfer, VK_ACCESS_2_TRANSFER_READ_BIT,
                       VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL}}},
                    {3,
                     {},
                     {{"kept", kept.handle(), kTransfer, 0, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0,
                       VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_GENERAL}}}},
                   c.cmds);
    EXPECT_EQ(report.barriers, 4u);
    EXPECT_EQ(report.layoutTransitions, 2u);
    c.submit(report.recorded.size());
  }
}

// A frame shaped like the renderer's: a compute pass writes draw arguments, a draw reads them as indirect arguments
// and renders a colour attachment, a compute pass samples it and writes a storage image, which the frame hands on to
// be copied out (an output in TRANSFER_SRC). Every barrier is derived by hand below.
GPU_TEST(FrameGraph, ARenderLikeChainGetsTheBarriersDerivedByHand) {
  gpu::Buffer draws(dev, 256, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
                    gpu::MemoryUse::DeviceLocal);
  gpu::Image color(dev, VK_FORMAT_R32_UINT, 16, 16, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                   VK_IMAGE_ASPECT_COLOR_BIT);
  gpu::Image result(dev, VK_FORMAT_R32_UINT, 16, 16, VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                    VK_IMAGE_ASPECT_COLOR_BIT);
  Commands c(dev);
  FrameGraph g;
  const FrameGraph::Resource d = g.buffer("draws"), col = g.image("color", color), res = g.image("result", result);
  const auto nothing = [](VkCommandBuffer) {};  // the barriers are the subject: the steps record no work
  g.pass("cull").step({FrameGraph::overwrites(d, ga::computeReadWrite)}, nothing);
  g.pass("draw").step({FrameGraph::reads(d, ga::indirect), FrameGraph::overwrites(col, ga::colorAttachment)}, nothing);
  g.pass("shade").step(
      {FrameGraph::reads(col, ga::computeSampled), FrameGraph::overwrites(res, ga::computeStorageImage)}, nothing);
  g.output(res, ga::transferRead);
  std::vector<RecordedBarrier> barriers;
  FrameGraph::Report report;
  {
    const CaptureBarriers capture(barriers);
    report = g.record(c.cmds, Commands::begin, nullptr);
  }
  EXPECT_EQ(report.recorded, (std::vector<std::string>{"cull", "draw", "shade"}));
  EXPECT_TRUE(report.dropped.empty());
  constexpr VkAccessFlags2 kStorage = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
  constexpr VkAccessFlags2 kAttachment = VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
  // By hand:
  //   "cull" (cmd 0): the frame boundary; `draws` overwritten with nothing before it: no barrier. Its access leaves
  //     a pending shader storage write (the read bit is no write to make available).
  //   "draw" (cmd 1): `draws` read as indirect arguments after the compute storage write: a global compute storage
  //     write -> draw-indirect indirect-command read; the colour image overwritten: from no stage to the attachment
  //     output's read and write, UNDEFINED -> COLOR_ATTACHMENT_OPTIMAL. One pipeline barrier.
  //   "shade" (cmd 2): the colour image sampled by compute after the attachment write: attachment output, attachment
  //     write -> compute sampled read, COLOR_ATTACHMENT_OPTIMAL -> SHADER_READ_ONLY_OPTIMAL; the result overwritten
  //     with nothing before it: from no stage to the compute storage read and write, UNDEFINED -> GENERAL. One
  //     pipeline barrier, two transitions, no global barrier.
  //   End of the frame: the output left as asked, after the compute storage write: compute, storage write ->
  //     transfer read, GENERAL -> TRANSFER_SRC_OPTIMAL.
  expectBarriers(
      barriers,
      {{0, {kBoundary}, {}},
       {1,
        {{kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT,
          VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT}},
        {{"color", color.handle(), VK_PIPELINE_STAGE_2_NONE, 0, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
          kAttachment, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}}},
       {2,
        {},
        {{"color", color.handle(), VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
          VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, kCompute, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
          VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL},
         {"result", result.handle(), VK_PIPELINE_STAGE_2_NONE, 0, kCompute, kStorage, VK_IMAGE_LAYOUT_UNDEFINED,
          VK_IMAGE_LAYOUT_GENERAL}}},
       {2,
        {},
        {{"result", result.handle(), kCompute, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, kTransfer,
          VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_GENERAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL}}}},
      c.cmds);
  EXPECT_EQ(report.barriers, 4u);
  EXPECT_EQ(report.layoutTransitions, 4u);
  c.submit(report.recorded.size());
}

// The renderer's frames through the graph: a pyramid the plan skips and light lists the shading does not read are
// dropped by the structure, not by a flag in the pass; the passes a frame needs are recorded in order.
GPU_TEST(FrameGraph, RendererDropsThePassesAFrameDoesNotRead) {
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

  fo.tiledLights = false;
  fo.readPyramid = false;
  fo.skipUselessPyramid = true;
  // Frames until the pyramid is skipped: from above the field nothing is occluded, so the plan stops building it.
  Result<FrameResult> f = (*renderer)->renderFrame(cam, fo);
  for (int i = 0; i < 4 && f.ok() && !f->stats.pyramid.skipped; ++i) f = (*renderer)->renderFrame(cam, fo);
  ASSERT_TRUE(f.ok());
  ASSERT_TRUE(f->stats.pyramid.skipped);
  // A skipped pyramid is not declared at all: the frame runs its late phase alone (FramePlan::lateOnly).
  EXPECT_FALSE(contains(f->stats.graph.passesRecorded, "depth pyramid"));
  EXPECT_FALSE(contains(f->stats.graph.passesRecorded, "cull early"));
  EXPECT_TRUE(contains(f->stats.graph.passesRecorded, "cull"));
  EXPECT_TRUE(contains(f->stats.graph.passesDropped, "light cull"));
  EXPECT_FALSE(contains(f->stats.graph.passesRecorded, "light cull"));
  EXPECT_TRUE(contains(f->stats.graph.passesRecorded, "shade")) << "the frame's colour is its product, read back or not";
  // The skipped passes took no GPU time.
  for (const auto& [name, ms] : f->stats.graph.passMs) EXPECT_NE(name, "depth pyramid");
}
