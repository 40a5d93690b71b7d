#include "visbuf/gpu/frame_graph.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

#include "visbuf/core/log.h"
#include "visbuf/gpu/check.h"
#include "visbuf/gpu/pipeline.h"

namespace visbuf::gpu {

namespace {

constexpr VkAccessFlags2 kWriteBits = VK_ACCESS_2_SHADER_WRITE_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT |
                                      VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT |
                                      VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_TRANSFER_WRITE_BIT |
                                      VK_ACCESS_2_HOST_WRITE_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT;

// One resource while the frame is recorded: its last write, the reads since, to whom that write is visible, and
// an image's layout.
struct State {
  VkPipelineStageFlags2 writeStages = 0;  // 0: not written since the frame boundary
  VkAccessFlags2 writeAccess = 0;
  VkPipelineStageFlags2 readStages = 0;   // since the last write (a later write waits for them)
  std::vector<Access> visible;            // since the last write: made visible to these stages and accesses
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;

  bool isVisible(const Access& a) const {
    return std::any_of(visible.begin(), visible.end(), [&](const Access& v) {
      return (a.stages & ~v.stages) == 0 && (a.access & ~v.access) == 0;
    });
  }
  void wrote(const Access& a) {
    writeStages = a.stages;
    writeAccess = a.access & kWriteBits;
    readStages = 0;
    visible.clear();
  }
};

// The barriers before one step: one global memory barrier (buffers, and images that keep their layout) and the
// image layout transitions.
struct Barriers {
  VkMemoryBarrier2 global{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  std::vector<VkImageMemoryBarrier2> images;

  void addGlobal(VkPipelineStageFlags2 srcStages, VkAccessFlags2 srcAccess, const Access& dst) {
    global.srcStageMask |= srcStages;
    global.srcAccessMask |= srcAccess;
    global.dstStageMask |= dst.stages;
    global.dstAccessMask |= dst.access;
  }
  void record(VkCommandBuffer cmd, FrameGraph::Report& report) const {
    const bool hasGlobal = global.dstStageMask != 0;
    if (!hasGlobal && images.empty()) return;
    VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
    di.memoryBarrierCount = hasGlobal ? 1 : 0;
    di.pMemoryBarriers = &global;
    di.imageMemoryBarrierCount = uint32_t(images.size());
    di.pImageMemoryBarriers = images.data();
    vkCmdPipelineBarrier2(cmd, &di);
    ++report.barriers;
    report.layoutTransitions += uint32_t(images.size());
  }
};

// The dependency `use` needs on what the frame did to the resource so far, added to `b`; the state updated.
void synchronise(State& s, const Image* image, const FrameGraph::Use& use, Barriers& b) {
  const Access& a = use.access;
  const bool write = use.mode != FrameGraph::Mode::Read;
  if (image && a.layout != s.layout) {
    VkImageMemoryBarrier2 ib{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
    ib.srcStageMask = s.writeStages | s.readStages;
    ib.srcAccessMask = s.writeAccess;
    ib.dstStageMask = a.stages;
    ib.dstAccessMask = a.access;
    ib.oldLayout = use.mode == FrameGraph::Mode::Overwrite ? VK_IMAGE_LAYOUT_UNDEFINED : s.layout;
    ib.newLayout = a.layout;
    ib.srcQueueFamilyIndex = ib.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    ib.image = image->handle();
    ib.subresourceRange = {image->aspect(), 0, image->mipLevels(), 0, image->layers()};
    b.images.push_back(ib);
    s.layout = a.layout;
    // The transition is a write, made visible to this use's stages and accesses.
    s.wrote(a);
    if (!write) {
      s.writeAccess = 0;
      s.readStages = a.stages;
    }
    s.visible.push_back(a);
    return;
  }
  if (write) {
    if (s.writeStages | s.readStages) b.addGlobal(s.writeStages | s.readStages, s.writeAccess, a);
    s.wrote(a);
    return;
  }
  if (s.writeStages && !s.isVisible(a)) {
    b.addGlobal(s.writeStages, s.writeAccess, a);
    s.visible.push_back(a);
  }
  s.readStages |= a.stages;
}

// One use per resource in a step: the stages and accesses of its uses together, the strongest mode.
std::vector<FrameGraph::Use> mergeUses(const std::vector<FrameGraph::Use>& uses, const FrameGraph& graph) {
  std::vector<FrameGraph::Use> out;
  for (const FrameGraph::Use& u : uses) {
    if (u.resource >= graph.resources()) {
      logMessage(LogLevel::Error, "frame graph: a step uses a resource the frame did not declare");
      std::abort();
    }
    auto it = std::find_if(out.begin(), out.end(), [&](const FrameGraph::Use& o) { return o.resource == u.resource; });
    if (it == out.end()) {
      out.push_back(u);
      continue;
    }
    if (it->access.layout != u.access.layout) {
      logMessage(LogLevel::Error, "frame graph: " + graph.name(u.resource) + " used in two layouts by one step");
      std::abort();
    }
    it->access.stages |= u.access.stages;
    it->access.access |= u.access.access;
    it->mode = std::max(it->mode, u.mode);
  }
  return out;
}

}  // namespace

FrameGraph::Resource FrameGraph::buffer(std::string name, bool persistent) {
  resources_.push_back({std::move(name), nullptr, VK_IMAGE_LAYOUT_UNDEFINED, persistent});
  return Resource(resources_.size() - 1);
}

FrameGraph::Resource FrameGraph::image(std::string name, const Image& image, VkImageLayout keepLayout) {
  resources_.push_back({std::move(name), &image, keepLayout, false});
  return Resource(resources_.size() - 1);
}

FrameGraph::Pass& FrameGraph::Pass::step(std::vector<Use> uses, Record run) {
  steps_.push_back({std::move(uses), std::move(run)});
  return *this;
}

FrameGraph::Pass& FrameGraph::Pass::prepare(std::vector<Use> uses, Record run) {
  steps_.push_back({std::move(uses), std::move(run), false});
  return *this;
}

FrameGraph::Pass& FrameGraph::Pass::sideEffect() {
  sideEffect_ = true;
  return *this;
}

FrameGraph::Pass& FrameGraph::pass(std::string name, std::string timer) {
  Pass& p = passes_.emplace_back();
  p.name_ = std::move(name);
  p.timer_ = std::move(timer);
  return p;
}

void FrameGraph::output(Resource r, Access final) { outputs_.emplace_back(r, final); }

FrameGraph::Report FrameGraph::record(std::span<const VkCommandBuffer> cmds,
                                      const std::function<void(VkCommandBuffer)>& begin, TimestampPool* timestamps) {
  Report report;
  for (Pass& p : passes_)
    for (Pass::Step& s : p.steps_) s.uses = mergeUses(s.uses, *this);

  // From the last pass back: a pass is kept when it has a side effect, writes persistent state, or writes what a
  // kept later pass or the outputs read. A kept pass needs what it reads and what it writes in part.
  std::vector<char> needed(resources_.size(), 0), keep(passes_.size(), 0);
  for (const auto& [r, a] : outputs_) needed[r] = 1;
  for (size_t i = passes_.size(); i-- > 0;) {
    const Pass& p = passes_[i];
    bool live = p.sideEffect_;
    for (const Pass::Step& s : p.steps_)
      for (const Use& u : s.uses)
        live = live || (u.mode != Mode::Read && (needed[u.resource] || resources_[u.resource].persistent));
    if (!live) {
      report.dropped.insert(report.dropped.begin(), p.name_);
      continue;
    }
    keep[i] = 1;
    for (size_t k = p.steps_.size(); k-- > 0;) {
      for (const Use& u : p.steps_[k].uses)
        if (u.mode == Mode::Overwrite) needed[u.resource] = 0;
      for (const Use& u : p.steps_[k].uses)
        if (u.mode != Mode::Overwrite) needed[u.resource] = 1;
    }
  }
  const size_t last = size_t(std::find(keep.rbegin(), keep.rend(), 1) - keep.rbegin());
  const size_t lastKept = passes_.size() - 1 - last;

  std::vector<State> state(resources_.size());
  for (size_t r = 0; r < resources_.size(); ++r) state[r].layout = resources_[r].keepLayout;
  size_t used = 0;
  for (size_t i = 0; i < passes_.size(); ++i) {
    if (!keep[i]) continue;
    const Pass& p = passes_[i];
    if (used == cmds.size()) {
      logMessage(LogLevel::Error, "frame graph: more passes than the " + std::to_string(cmds.size()) +
                                      " command buffers (at " + p.name_ + ")");
      std::abort();
    }
    VkCommandBuffer cmd = cmds[used++];
    begin(cmd);
    if (used == 1) {
      // The frame boundary: whatever ran before (earlier frames, the host's commands on the outputs) is done
      // and its writes visible; every resource starts without a pending access.
      if (timestamps) timestamps->reset(cmd);
      memoryBarrier(cmd, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_WRITE_BIT,
                    VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT);
      ++report.barriers;
    }
    uint32_t timer = UINT32_MAX;
    for (size_t k = 0; k < p.steps_.size(); ++k) {
      Barriers b;
      for (const Use& u : p.steps_[k].uses) synchronise(state[u.resource], resources_[u.resource].image, u, b);
      b.record(cmd, report);
      if (timer == UINT32_MAX && p.steps_[k].timed && timestamps && !p.timer_.empty())
        timer = timestamps->begin(cmd, p.timer_);
      p.steps_[k].run(cmd);
    }
    if (timer != UINT32_MAX) timestamps->end(cmd, timer);
    if (i == lastKept) {
      // The outputs in their final state, and every kept layout restored for the next frame.
      Barriers b;
      for (auto [r, a] : outputs_) {
        if (a.layout == VK_IMAGE_LAYOUT_UNDEFINED) a.layout = state[r].layout;  // left in the layout it is in
        synchronise(state[r], resources_[r].image, {r, a, Mode::Read}, b);
      }
      for (size_t r = 0; r < resources_.size(); ++r)
        if (resources_[r].image && resources_[r].keepLayout != VK_IMAGE_LAYOUT_UNDEFINED &&
            state[r].layout != resources_[r].keepLayout)
          synchronise(state[r], resources_[r].image,
                      {Resource(r), {VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, 0, resources_[r].keepLayout}, Mode::Read}, b);
      b.record(cmd, report);
    }
    VK_CHECK(vkEndCommandBuffer(cmd));
    report.recorded.push_back(p.name_);
  }
  return report;
}

}  // namespace visbuf::gpu
