// visbuf bench --in-flight K[,K...]: steady-state frame throughput of Renderer::record with K frames queued (the
// bench's own fence ring, the only wait in the loop) against Renderer::renderFrame (record, submit, wait), over the
// same cameras of the bench path with 5 % of the objects moving every frame (SceneMotion). Each run starts from a
// fresh renderer and motion, so every run draws the same frames; the runs alternate record / renderFrame, --pairs
// times, and the ratio is taken pair by pair. The error beside it: the colour of one more frame, recorded by the
// ring and copied out, against renderFrame's colour of the same frame (same camera, same scene changes).
#include "bench_in_flight.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>
#include <glm/gtc/packing.hpp>

#include "cli_checks.h"
#include "stats_output.h"
#include "visbuf/gpu/check.h"
#include "visbuf/gpu/device.h"
#include "visbuf/gpu/resources.h"
#include "visbuf/render/renderer.h"
#include "visbuf/render/scene_motion.h"

namespace visbuf::tools {

namespace {

constexpr double kMoving = 0.05;

struct Run {
  double framesPerSecond = 0.0;
  std::vector<float> lastColor;  // RGBA, the frame after the timed ones
};

// The colour image of a recorded frame (TRANSFER_SRC_OPTIMAL, its writes visible: record()'s contract) to floats.
std::vector<float> copyColor(gpu::Device& device, const FrameImage& image, uint32_t w, uint32_t h) {
  gpu::Buffer buffer(device, VkDeviceSize(w) * h * 8, VK_BUFFER_USAGE_TRANSFER_DST_BIT, gpu::MemoryUse::HostVisible);
  VkCommandBuffer cmd = device.beginOneShot();
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {w, h, 1};
  vkCmdCopyImageToBuffer(cmd, image.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer.handle(), 1, &region);
  device.submitOneShot(cmd);
  std::vector<float> out(size_t(w) * h * 4);
  const auto* halves = static_cast<const uint16_t*>(buffer.mapped());
  for (size_t i = 0; i < out.size(); ++i) out[i] = glm::unpackHalf1x16(halves[i]);
  return out;
}

// `frames` frames after `warmup`, then one more whose colour is kept. ring: record() with the renderer's
// framesInFlight frames queued; otherwise renderFrame.
Result<Run> runFrames(gpu::Device& device, const Scene& scene, const RendererConfig& rc,
                      const std::vector<Camera>& path, uint32_t warmup, uint32_t frames, bool ring) {
  auto created = Renderer::create(device, scene, rc);
  if (!created) return created.error();
  Renderer& r = **created;
  auto motion = SceneMotion::create(scene, {.moving = kMoving, .churn = 0.0, .seed = 1});
  if (!motion) return motion.error();
  VkDevice dev = device.device();
  std::vector<VkFence> fences(rc.framesInFlight, VK_NULL_HANDLE);
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
  for (VkFence& f : fences) VK_CHECK(vkCreateFence(dev, &fci, nullptr, &f));
  Run run;
  Status failed;
  using Clock = std::chrono::steady_clock;
  Clock::time_point start;
  const uint32_t total = warmup + frames + 1;
  FrameInputs inputs;
  inputs.options.readColor = false;
  RecordedFrame last;
  for (uint32_t f = 0; f < total && failed; ++f) {
    if (f == warmup) {
      VK_CHECK(vkDeviceWaitIdle(dev));
      start = Clock::now();
    }
    const bool keep = f + 1 == total;
    if (keep) {
      VK_CHECK(vkDeviceWaitIdle(dev));
      run.framesPerSecond = frames / std::chrono::duration<double>(Clock::now() - start).count();
    }
    const Camera& camera = path[std::min<size_t>(f, path.size() - 1)];
    if (auto moved = motion->apply(r, f); !moved) {
      failed = moved.error();
      break;
    }
    if (!ring) {
      FrameOptions fo;
      fo.readColor = keep;
      auto frame = r.renderFrame(camera, fo);
      if (!frame) failed = frame.error();
      else if (keep) run.lastColor = std::move(frame->color);
      continue;
    }
    VkFence fence = fences[f % fences.size()];
    VK_CHECK(vkWaitForFences(dev, 1, &fence, VK_TRUE, UINT64_MAX));  // frame f - K has finished
    inputs.camera = camera;
    auto recorded = r.record(inputs);
    if (!recorded) {
      failed = recorded.error();
      break;
    }
    VK_CHECK(vkResetFences(dev, 1, &fence));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = uint32_t(recorded->commandBuffers.size());
    si.pCommandBuffers = recorded->commandBuffers.data();
    VK_CHECK(vkQueueSubmit(device.queue(), 1, &si, fence));
    if (keep) last = *recorded;
  }
  VK_CHECK(vkDeviceWaitIdle(dev));
  if (failed && ring) run.lastColor = copyColor(device, last.color, last.width, last.height);
  for (VkFence f : fences) vkDestroyFence(dev, f, nullptr);
  if (!failed) return failed.error();
  return run;
}

}  // namespace

int runInFlightBench(const BenchCommand& c, gpu::Device& device, const std::vector<Scene>& scenes,
                     uint32_t width, uint32_t height, const std::filesystem::path& out) {
  nlohmann::json rows = nlohmann::json::array();
  std::string md = fmt::format(
      "# visbuf bench --in-flight\n\nDevice: {}. Command: `{}`. Date: {}.\n\nSteady-state throughput of "
      "`Renderer::record` with K frames in flight against `renderFrame` (record, submit, wait), {} frames after {} "
      "of warm-up, {:.0f} % of the objects moving every frame; the ratio per interleaved pair. Error: the colour of the "
      "next frame through `record` against `renderFrame`'s (max per channel).\n\n"
      "| objects | size | in flight | record frames/s | renderFrame frames/s | ratio (median) | min - max | max colour "
      "difference |\n|---|---|---|---|---|---|---|---|\n",
      device.name(), c.commandLine, utcNow(), c.frames, c.warmup, 100.0 * kMoving);
  for (const Scene& scene : scenes) {
    const std::vector<Camera> path = benchCameraPath(scene, c.warmup, c.frames + 1);
    for (uint32_t k : c.inFlight) {
      RendererConfig rc;
      rc.width = width;
      rc.height = height;
      rc.framesInFlight = k;
      std::vector<double> ratios, recordFps, renderFps;
      double maxDiff = 0.0;
      // One run first, not counted: the device's first use of each pipeline (lavapipe compiles on first use).
      if (auto warm = runFrames(device, scene, rc, path, c.warmup, c.frames, true); !warm) return benchFail(warm.error());
      for (uint32_t p = 0; p < c.pairs; ++p) {
        auto a = runFrames(device, scene, rc, path, c.warmup, c.frames, true);
        auto b = runFrames(device, scene, rc, path, c.warmup, c.frames, false);
        if (!a) return benchFail(a.error());
        if (!b) return benchFail(b.error());
        recordFps.push_back(a->framesPerSecond);
        renderFps.push_back(b->framesPerSecond);
        ratios.push_back(a->framesPerSecond / b->framesPerSecond);
        for (size_t i = 0; i < a->lastColor.size() && i < b->lastColor.size(); ++i)
          maxDiff = std::max(maxDiff, double(std::abs(a->lastColor[i] - b->lastColor[i])));
        std::printf("  %zu objects, %u in flight, pair %u: record %.1f frames/s, renderFrame %.1f frames/s, ratio %.3f\n",
                    scene.objects.size(), k, p + 1, a->framesPerSecond, b->framesPerSecond, ratios.back());
      }
      const double lo = *std::min_element(ratios.begin(), ratios.end());
      const double hi = *std::max_element(ratios.begin(), ratios.end());
      std::printf("%zu objects at %ux%u, %u in flight: record / renderFrame %.3fx (min %.3f, max %.3f, %u pairs); "
                  "colour max difference %.6f\n",
                  scene.objects.size(), width, height, k, median(ratios), lo, hi, c.pairs, maxDiff);
      rows.push_back({{"objects", scene.objects.size()}, {"width", width}, {"height", height}, {"inFlight", k},
                      {"frames", c.frames}, {"warmup", c.warmup}, {"pairs", c.pairs}, {"moving", kMoving},
                      {"recordFramesPerSecond", recordFps}, {"renderFrameFramesPerSecond", renderFps},
                      {"ratios", ratios}, {"ratioMedian", median(ratios)}, {"maxColorDifference", maxDiff}});
      md += fmt::format("| {} | {}x{} | {} | {:.1f} | {:.1f} | **{:.2f}x** | {:.2f} - {:.2f} | {:.6f} |\n",
                        scene.objects.size(), width, height, k, median(recordFps), median(renderFps), median(ratios),
                        lo, hi, maxDiff);
    }
  }
  nlohmann::json j;
  j["command"] = c.commandLine;
  j["device"] = device.name();
  j["date"] = utcNow();
  j["inFlight"] = rows;
  if (Status s = writeJsonFile((out / "bench.json").string(), j); !s) return benchFail(s.error());
  if (Status s = writeTextFile((out / "bench.md").string(), md); !s) return benchFail(s.error());
  std::printf("wrote %s and %s\n", printable((out / "bench.json").string()).c_str(),
              printable((out / "bench.md").string()).c_str());
  return 0;
}

}  // namespace visbuf::tools
