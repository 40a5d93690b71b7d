// A frame as a declared graph (the setup/execute split of Filament's FrameGraph and Granite's RenderGraph): each
// pass declares which resources it reads and writes, with the pipeline stages, the access and, for an image, the
// layout; the graph then
//   - drops every pass whose writes nothing reads (a pass that reads nothing the frame hands on is not recorded),
//   - derives the barriers and image layout transitions between the passes that remain, and
//   - records each pass into its own command buffer, all to be submitted in order in one submit (Mesa 22.3's
//     lavapipe crashed on a dispatch, a barrier and timestamps in one command buffer; see docs/architecture.md).
// Synchronisation inside a pass (between the dispatches of a pyramid, a scan) stays the pass's own.
#pragma once

#include <deque>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include "visbuf/gpu/resources.h"

namespace visbuf::gpu {

class TimestampPool;

// How a step of a pass touches a resource.
struct Access {
  VkPipelineStageFlags2 stages = VK_PIPELINE_STAGE_2_NONE;
  VkAccessFlags2 access = VK_ACCESS_2_NONE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;  // images: the layout the step needs
};

// Both accesses (in the first one's layout).
constexpr Access operator|(Access a, Access b) { return {a.stages | b.stages, a.access | b.access, a.layout}; }

// The accesses the passes use, by what they do.
namespace access {
inline constexpr VkPipelineStageFlags2 kDepthStages =
    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
inline constexpr VkPipelineStageFlags2 kRasterShaders =
    VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
inline constexpr VkAccessFlags2 kStorageReadWrite =
    VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
// Compute shaders: storage buffers (read, write, both), sampled images and texel buffers, storage images.
inline constexpr Access computeRead{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                                    VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_UNIFORM_READ_BIT};
inline constexpr Access computeReadWrite{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, kStorageReadWrite};
inline constexpr Access computeSampled{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT,
                                       VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
inline constexpr Access computeStorageImage{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, kStorageReadWrite,
                                            VK_IMAGE_LAYOUT_GENERAL};
// Indirect arguments and counts (draws and dispatches).
inline constexpr Access indirect{VK_PIPELINE_STAGE_2_DRAW_INDIRECT_BIT, VK_ACCESS_2_INDIRECT_COMMAND_READ_BIT};
// Raster shaders reading storage buffers.
inline constexpr Access rasterRead{kRasterShaders, VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                                                       VK_ACCESS_2_SHADER_SAMPLED_READ_BIT |
                                                       VK_ACCESS_2_UNIFORM_READ_BIT};
inline constexpr Access rasterReadWrite{kRasterShaders, kStorageReadWrite};
// Attachments: written (and blended or loaded), and depth tested and written, or tested only.
inline constexpr Access colorAttachment{VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
                                        VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                                        VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
inline constexpr Access depthAttachment{
    kDepthStages, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
    VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL};
// Transfers: fills, updates, clears and copies.
inline constexpr Access transferWrite{VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL};
inline constexpr Access transferRead{VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT,
                                     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
// Everything, for what a pass does through another path (a host's command, a debug image): reads and writes.
inline constexpr Access any{VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                            VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT};
// The same access in another image layout (a storage image in GENERAL read as a sampled one, ...).
constexpr Access inLayout(Access a, VkImageLayout layout) { return {a.stages, a.access, layout}; }
}  // namespace access

class FrameGraph {
 public:
  using Resource = uint32_t;
  static constexpr Resource kNoResource = UINT32_MAX;

  // A buffer, or any buffer-like state several buffers share (the scene's records, the counters). Only memory
  // dependencies are derived for it. persistent: later frames read what this frame writes (occlusion history,
  // draw lists a frozen frame redraws), so a pass that writes it is never dropped.
  Resource buffer(std::string name, bool persistent = false);
  // An image. keepLayout (not UNDEFINED): its content and that layout carry from frame to frame (the graph returns
  // it to the layout at the end of the frame). UNDEFINED: its content at the start of the frame is not needed.
  Resource image(std::string name, const Image& image, VkImageLayout keepLayout = VK_IMAGE_LAYOUT_UNDEFINED);

  enum class Mode : uint8_t {
    Read,       // reads
    Write,      // writes part (or reads and writes): what earlier passes wrote is still needed
    Overwrite,  // writes it all: what earlier passes wrote is not (an image's content is discarded: UNDEFINED)
  };
  struct Use {
    Resource resource = 0;
    Access access;
    Mode mode = Mode::Read;
  };
  static Use reads(Resource r, Access a) { return {r, a, Mode::Read}; }
  static Use writes(Resource r, Access a) { return {r, a, Mode::Write}; }
  static Use overwrites(Resource r, Access a) { return {r, a, Mode::Overwrite}; }

  using Record = std::function<void(VkCommandBuffer)>;
  class Pass {
   public:
    // A step: the barriers its uses need are recorded before it runs. Steps run in order in the pass's command
    // buffer; the pass's timer spans all of them (after the first step's barriers).
    Pass& step(std::vector<Use> uses, Record run);
    // A step before the timer starts (clears that are not the pass's work); before every step().
    Pass& prepare(std::vector<Use> uses, Record run);
    // Kept even when nothing of the frame reads what it writes: it writes for the host (counters, readback).
    Pass& sideEffect();

   private:
    friend class FrameGraph;
    std::string name_;
    std::string timer_;  // empty: untimed
    bool sideEffect_ = false;
    struct Step {
      std::vector<Use> uses;
      Record run;
      bool timed = true;
    };
    std::vector<Step> steps_;
  };
  // A pass, recorded in declaration order; timer: the name its GPU time is reported under (empty: untimed).
  Pass& pass(std::string name, std::string timer = {});

  // What the frame hands on: its writers are kept, and it is left in `final` at the end of the frame, its writes
  // available and visible to `final`'s stages and access (an image with final.layout UNDEFINED: left in the
  // layout its last use left it in).
  void output(Resource r, Access final);

  struct Report {
    std::vector<std::string> recorded;  // the passes recorded, in order (one command buffer each)
    std::vector<std::string> dropped;   // the passes whose writes nothing read
    uint32_t barriers = 0;              // pipeline barriers the graph recorded
    uint32_t layoutTransitions = 0;     // image layout transitions among them
  };
  // Drops the unread passes, then records the others, one command buffer each from `cmds` (each begun with
  // `begin`, ended here), the first starting with the frame boundary (every earlier command's writes made
  // available and visible) and `timestamps`' reset.
  Report record(std::span<const VkCommandBuffer> cmds, const std::function<void(VkCommandBuffer)>& begin,
                TimestampPool* timestamps);

  const std::string& name(Resource r) const { return resources_[r].name; }
  size_t resources() const { return resources_.size(); }

 private:
  struct ResourceInfo {
    std::string name;
    const Image* image = nullptr;
    VkImageLayout keepLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    bool persistent = false;
  };
  std::vector<ResourceInfo> resources_;
  std::deque<Pass> passes_;  // (references to them stay valid while more are declared)
  std::vector<std::pair<Resource, Access>> outputs_;
};

}  // namespace visbuf::gpu
