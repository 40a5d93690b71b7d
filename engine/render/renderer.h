// The public API of the visbuf module, used by tools/visbuf exactly as a host engine would:
//
//   auto device = gpu::Device::create({});          // or gpu::Device::adopt(hostHandles)
//   auto renderer = Renderer::create(**device, scene, {.width = 1920, .height = 1080});
//   auto frame = (*renderer)->renderFrame(camera, {});  // colour, IDs, per-pass GPU times, stats
//
// The renderer owns the GPU mirror of the scene, the frame's targets and pipelines. Two ways to run a frame:
//   - renderFrame records, submits and waits, then reads back what was asked for (tools, tests, headless use);
//   - record returns the frame's command buffers for the host to submit itself, with up to
//     RendererConfig::framesInFlight frames queued, and its output images for the host to compose or present:
//
//       auto frame = renderer->record({camera, options});       // no wait unless the ring is full (below)
//       submit(frame->commandBuffers, hostCommandsThatReadFrame->color, fence[frame->index % N]);
//
// The scene may change between frames: setTransforms, setVisible, addObject, removeObject (only the changed
// object records are uploaded, by the next frame's first command buffer, and scattered into place by one dispatch).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/gpu/device.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// GBuffer: the visbuf path's culling (both occlusion phases) feeding a deferred G-buffer raster + lighting pass
// (the baseline of the benchmark; no IDs).
enum class RenderPath { Visbuf, Forward, GBuffer };
enum class CullMode { None, Frustum, Occlusion };
// How the visbuf path's shading pass runs: one "ubershader" dispatch over every pixel (Uber), the ubershader
// over the pixels that show anything (Covered: covered_pixels.comp lists them first), or material
// classification followed by one indirect dispatch per material (Classified, passes/classify_pass.h). Auto:
// the faster one for the device type, as measured by the benchmark (docs/benchmarks.md, defaultShading).
enum class ShadingMode { Auto, Uber, Classified, Covered };

const char* renderPathName(RenderPath path);
const char* cullModeName(CullMode mode);
const char* shadingModeName(ShadingMode mode);
ShadingMode parseShadingMode(const std::string& name);  // "uber", "classified", "covered", anything else: Auto
// What Auto resolves to on a device (CPU implementations such as lavapipe, or GPUs) until a frame's coverage is
// known: a CPU device then takes the ubershader while frames show something in most pixels (FrameHistory).
ShadingMode defaultShading(const gpu::Device& device);
ShadingMode defaultShadingFor(bool cpuDevice);  // the same, by device type
// The micro-raster's object size bound (pixels per side) when FrameOptions::swRasterPixels is unset: 94 on a CPU
// device, 64 on a GPU.
float defaultSwRasterPixels(bool cpuDevice);
// The micro-raster's bound on screen box area per triangle (pixels) when FrameOptions::swRasterArea is unset, on
// either device type.
inline constexpr float kDefaultSwRasterArea = 128.0f;
// FrameOptions::swRasterArea's upper limit: a triangle's box of SW_RASTER_MAX_EXTENT pixels per side.
inline constexpr float kMaxSwRasterArea = 9216.0f;

// Culling bounds of skinned instances: Joints = a sphere from the joints' reach (CPU, double precision,
// provably containing every skinned vertex: animation.h); Gpu = from the skinned vertices themselves, reduced
// on the GPU: their AABB's centre and the largest distance from it (tighter; the forward path still culls with
// the joint-reach sphere).
enum class SkinBounds { Joints, Gpu };
const char* skinBoundsName(SkinBounds bounds);

struct RendererConfig {
  uint32_t width = 1920;
  uint32_t height = 1080;
  uint32_t drawCapacity = 0;  // max draw commands per phase and draw list; 0 = one per object (never overflows)
  bool forceWideIds = false;  // use the 64-bit ID target even when 32 bits fit
  SkinBounds skinBounds = SkinBounds::Joints;
  // record(): frames whose commands may be pending at once (1..4). Each has its own frame constants, counter
  // readback, timestamp queries, descriptor set and command buffers.
  uint32_t framesInFlight = 2;
  // addObject(): object slots reserved beyond the scene's (every draw list gets room for them).
  uint32_t spareObjects = 0;
};

// One object moved (Renderer::setTransforms): its new object -> world transform.
struct ObjectTransform {
  uint32_t object = 0;
  glm::dmat4 transform{1.0};
};

// One skinned instance as the GPU holds it after the last frame (Renderer::readSkinnedInstance; tests, tools).
struct SkinnedInstanceReadback {
  uint32_t object = 0;                        // Scene::objects index
  std::vector<gpu::SkinnedVertex> vertices;   // skin space, in the rest mesh's vertex order
  std::vector<uint32_t> tangents;             // octahedral, same order; empty when the mesh has no tangents
  glm::vec4 bounds{0.0f};                     // the culling sphere of its mesh slot (skin space)
};

// Software micro-raster of small objects (FrameOptions::swRaster).
enum class SwRasterMode { Auto, On, Off };
const char* swRasterModeName(SwRasterMode mode);
SwRasterMode parseSwRasterMode(const std::string& name);  // "on" | "off" | anything else: Auto
// Where the micro-raster's fragments meet the raster's (FrameOptions::swResolve).
enum class SwResolve { Auto, Merge, Shading };
const char* swResolveName(SwResolve mode);
SwResolve parseSwResolve(const std::string& name);  // "merge" | "shading" | anything else: Auto

struct FrameOptions {
  RenderPath path = RenderPath::Visbuf;
  CullMode cull = CullMode::Occlusion;
  float lodErrorPixels = 1.0f;  // <= 0: LOD off (always the full mesh)
  bool readColor = true;        // read the colour image back (RGBA float, linear)
  bool readIds = false;         // IDs per pixel (object + 1, triangle in its LOD): visbuf decodes its target;
                                // the forward path then writes them from a second pipeline variant
  bool readDraws = false;       // return the IDs of the objects drawn (visbuf: from the GPU's commands)
  bool freezeCulling = false;   // visbuf: redraw the last culled frame's draw lists (no cull, no pyramid), so
                                // the camera can move on and show what that frame culled
  bool readPyramid = false;     // read every depth pyramid level back (occlusion mode)
  bool countOverdraw = false;   // debug: count raster writes per pixel (FrameResult.overdraw)
  bool readAttributes = false;   // visbuf: the shading pass's reconstruction per pixel (FrameResult.attributes);
                                // G-buffer: the position rebuilt from depth and the depth (slots 0..3, 7) only
  double animationTime = 0.0;   // seconds: the pose of every skinned instance (plus its own time offset)
  bool tiledLights = true;       // visbuf: shade each pixel with its 16x16 tile's light list (light cull pass);
                                // false: every pixel loops over every point light (the reference, no culling)
  bool skipUselessPyramid = true;  // occlusion mode: when the pyramid occluded nothing, or objects that would have
                                   // cost the raster less than half the pyramid's own GPU time, skip it (and the
                                   // occlusion test) for the next kPyramidProbeInterval frames
  // Samples per pixel: 1 (no MSAA), 2 or 4 where supportedMsaaSamples() lists it. visbuf: multisampled ID and
  // depth targets, each pixel shaded once where its samples agree and once per distinct ID where they differ;
  // forward: multisampled colour + depth with a hardware resolve (the reference). Refused (InvalidArgument) for the
  // G-buffer path, scenes with BLEND materials (the transparency pass is single-sampled), countOverdraw,
  // readAttributes and the forward path's readIds. The multisampled targets and pipelines are created by the
  // first frame that asks for a count.
  uint32_t msaa = 1;
  // Software micro-raster (visbuf path): objects whose screen box is at most swRasterPixels per side (and wholly
  // beyond the near plane) are rasterised in compute (sw_raster_pass) instead of by the hardware raster, then
  // merged into the same ID target and depth. Not used for MSAA, countOverdraw, masked or capped draw lists.
  // Auto: on, and on a GPU only while it takes enough triangles to pay for its merges (renderer.cpp,
  // defaultSwRaster); On: whenever it takes anything. A frame in which it did not pay skips it for 16 frames.
  SwRasterMode swRaster = SwRasterMode::Auto;
  // Where the micro-raster's fragments meet the hardware raster's: merged into the ID target and depth (two
  // full-screen passes), or resolved by the pyramid and the shading, which take the nearer fragment per pixel
  // themselves (the same image). Resolved only where nothing else reads the target or the depth: frames that read
  // IDs back, hand them to a host (record()), cull lights, draw transparency, classify materials or use MSAA always
  // merge. Auto: resolved on both device types (the resolve reads the micro-raster's buffer through a texel view; on
  // lavapipe that costs less than the two full-screen merges: docs/benchmarks.md).
  SwResolve swResolve = SwResolve::Auto;
  // (0, SW_RASTER_MAX_EXTENT - 2]; unset: the device's (defaultSwRasterPixels): on lavapipe its hardware raster
  // costs about 4x the micro-raster per triangle, so the largest bound pays there (the peer view, 1024x768: 10k
  // kittens 37-39 ms against 40-41 at 64 px, 100k 123 against 133, 1M 247 against 262-274).
  std::optional<float> swRasterPixels;
  // (0, kMaxSwRasterArea]: an object (or cluster) goes to the micro-raster only while its screen box area divided by
  // its triangles is at most this many pixels, since a lane loops over a triangle's box serially. Unset:
  // kDefaultSwRasterArea, 128, where the hardware raster's per-triangle setup costs more than the micro-raster's
  // longer loops: against 32, lavapipe's peer view (1024x768, interleaved pairs) took 0.83x / 0.90x / 0.91x the frame
  // time at 10k / 100k / 1M kittens, an H200's 0.92x at 100k, 0.88x at 1M and 0.955x for 1M at 1920x1080 in the
  // field view (the same image bar edge ties).
  std::optional<float> swRasterArea;
  // Cluster culling (visbuf and G-buffer paths, culled frames): an object the hardware raster would draw whole, whose
  // LOD level has more than CLUSTER_TRIANGLES triangles, is drawn as its clusters that survive the frustum, their
  // back-face cone and (late phase) the depth pyramid; the small ones go to the micro-raster. Skinned instances are
  // always drawn whole.
  bool clusters = true;
  // Early cluster occlusion (occlusion culling with clusters): the early phase also tests the clusters of last frame's
  // visible objects against the pyramid the previous frame built and defers the ones it hides to a retest against
  // this frame's pyramid in the late phase (config.h CULL_CLUSTER_RETEST). The image is the same either way; off
  // draws every front-facing cluster of last frame's visible set in the early phase.
  bool earlyClusterOcclusion = true;
  ShadingMode shading = ShadingMode::Auto;  // visbuf path; readAttributes and MSAA frames always use the
                                            // ubershader over every pixel (its attributes / MSAA variant)
};

// How the visibility target's bits are split (DESIGN.md property 4).
struct IdEncoding {
  bool wide = false;            // rg32ui (64 bits) instead of r32ui
  uint32_t triangleBits = 0;    // narrow: low bits hold the triangle index
  uint32_t slotBits = 0;        // bits needed for a draw slot (capacity)
  std::string describe() const;
};

// A frame's statistics, grouped by the pass that produces them (the structs are named after the pass files of
// engine/passes); what belongs to no one pass (the frame, the visibility target, memory) stays at the top.

// cull_pass: both phases of the compute cull, with the LOD choice.
struct CullStats {
  uint32_t objectsTested = 0;
  uint32_t frustumCulled = 0;
  uint32_t occlusionCulled = 0;  // late phase: behind the depth pyramid
  uint32_t subpixelCulled = 0;   // late phase: bounds cover no pixel centre
  uint32_t refineTested = 0;     // late phase: tested again at a finer pyramid level (the coarse one kept them)
  uint32_t refineOccluded = 0;   // ... and occluded there (part of occlusionCulled)
  uint32_t drawsEarly = 0;       // occlusion mode: draws of the early phase (last frame's visible set)
  uint32_t drawsLate = 0;        // occlusion mode: draws of the late phase (newly visible)
  uint32_t drawsAppended = 0;    // draws the cull pass produced (visible objects)
  uint32_t drawsRendered = 0;    // min(appended, capacity)
  uint32_t drawCapacity = 0;     // per phase, all draw lists together
  uint32_t drawOverflow = 0;     // visible objects dropped for lack of capacity (reported, never silent)
  std::vector<uint32_t> lodHistogram;  // objects drawn per LOD level (whole or as clusters)
  bool cullingFrozen = false;    // this frame reused an earlier frame's draw lists
  // Cluster culling (FrameOptions::clusters): objects drawn as clusters, their clusters tested, culled by the
  // frustum, by their back-face cone, by the depth pyramid (or covering no pixel centre), and the draws made of
  // the rest (part of drawsRendered: one per run of consecutive hardware clusters, one per micro-raster cluster).
  struct Clusters {
    uint32_t objects = 0, tested = 0, frustumCulled = 0, backfacing = 0, occluded = 0, draws = 0;
    // Early cluster occlusion: clusters the early phase deferred (last frame's pyramid hid them), and those of them
    // the late retest drew (the rest are counted in `occluded`).
    uint32_t deferred = 0, recovered = 0;
  } clusters;
};

// sw_raster_pass: the software micro-raster and its merges.
struct SwRasterStats {
  bool on = false;          // this frame routed small objects to the micro-raster
  uint32_t draws = 0;       // of CullStats::drawsRendered: the micro-raster's
  uint64_t triangles = 0;   // of FrameStats::trianglesDrawn: the micro-raster's
  bool resolved = false;    // its fragments were resolved by the pyramid and the shading, not merged (swResolve)
  uint32_t oversize = 0;    // triangles it could not take (box over SW_RASTER_MAX_EXTENT or behind the near plane:
                            // only a frozen frame's moved camera can cause it); reported, never silent
};

// depth_pyramid_pass.
struct PyramidStats {
  uint32_t levels = 0;   // levels built this frame (0: no pyramid pass)
  bool skipped = false;  // occlusion mode, but the last pyramid hid nothing or less than it cost: skipped this frame
};

// skin_pass (and the CPU pose evaluation that feeds it).
struct SkinStats {
  uint32_t instances = 0;        // animated instances in the scene
  uint64_t vertices = 0;         // their vertices (all rewritten when the pose changes)
  bool ran = false;              // this frame ran the skinning pass (false: static scene, or a paused pose)
  double animationCpuMs = 0.0;   // CPU time to evaluate the poses (included in FrameStats::cpuRecordMs)
  std::string bounds;            // skinned scenes: the culling bounds used (skinBoundsName), else empty
};

// light_cull_pass (and the point lights it reads).
struct LightCullStats {
  uint32_t pointLights = 0;      // in the scene (0: no light cull pass, no light buffers)
  bool culled = false;           // this frame ran the light cull pass (visbuf path, tiledLights, point lights)
  uint32_t tileOverflow = 0;     // tiles whose light list overflowed LIGHTS_PER_TILE (reported, never silent)
  uint32_t dropped = 0;          // (tile, light) pairs dropped by that overflow
  uint32_t maxPerTile = 0;       // longest tile list before clamping
  double meanPerTile = 0.0;      // kept (tile, light) pairs / tiles
  uint64_t bytes = 0;            // GPU memory of the point lights and the tile lists
};

// shade_pass and classify_pass: the visbuf path's shading.
struct ShadeStats {
  // The mode used. Classified only: the materials with pixels, the (tile, material) pairs (= workgroups of all
  // shading dispatches) and, per scene material, its 8x8 tiles and pixels on screen.
  ShadingMode mode = ShadingMode::Uber;
  uint32_t materialsPresent = 0;
  uint32_t classifiedTiles = 0;
  std::vector<uint32_t> materialTiles;
  std::vector<uint32_t> materialPixels;
  uint32_t perSamplePixels = 0;  // MSAA: pixels whose samples differ, shaded once per distinct ID
};

// transparent_pass: BLEND objects, CPU-culled and sorted.
struct TransparentStats {
  uint32_t draws = 0;
  uint64_t triangles = 0;  // (not in FrameStats::trianglesDrawn)
};

// object_upload_pass: scene changes applied by this frame (setTransforms, setVisible, addObject, removeObject, rigid
// animation).
struct UploadStats {
  uint32_t objects = 0;  // object records rewritten
  uint64_t bytes = 0;    // bytes uploaded for them (each record and its object ID: 68 bytes)
};

// The frame graph (engine/gpu/frame_graph.h): per pass its GPU time, and what the graph derived.
struct GraphStats {
  std::vector<std::pair<std::string, double>> passMs;  // GPU time per pass (timer steps), recording order
  // The passes recorded (one command buffer each, in order), the passes dropped because nothing read what they
  // write (a skipped pyramid, untiled lights), and the barriers it derived between passes (image layout
  // transitions among them).
  std::vector<std::string> passesRecorded, passesDropped;
  uint32_t barriers = 0, layoutTransitions = 0;
};

struct FrameStats {
  std::string device;
  RenderPath path = RenderPath::Visbuf;
  uint32_t width = 0, height = 0;
  uint32_t objects = 0;
  uint64_t frameIndex = 0;      // frames recorded before this one (renderFrame and record count alike)
  CullStats cull;
  SwRasterStats sw;
  PyramidStats pyramid;
  SkinStats skin;
  LightCullStats lights;
  ShadeStats shade;
  TransparentStats transparent;
  UploadStats upload;
  GraphStats graph;
  // The visibility target: triangles of the hardware raster and the micro-raster together, and (visbuf path,
  // single-sampled) the pixels whose ID shows something; trianglesDrawn / coveredPixels is the triangles per
  // covered pixel (a visibility buffer's ideal is about 1).
  uint64_t trianglesDrawn = 0;
  uint32_t coveredPixels = 0;
  IdEncoding ids;
  uint32_t msaaSamples = 1;     // samples per pixel of this frame's raster targets
  double gpuMs = 0.0;           // sum of pass times
  double cpuRecordMs = 0.0;     // CPU time to cull (forward) and record
  double wallMs = 0.0;          // submit to fence, plus readback conversion
  uint64_t sceneBytes = 0;      // GPU memory of the scene mirror
  uint32_t textureClasses = 0;        // baked texture classes (2D array images) of the scene
  uint64_t textureBytes = 0;          // their texel bytes on the GPU (part of sceneBytes)
  uint32_t texturesDecompressed = 0;  // BC classes expanded to RGBA8: the device lacks textureCompressionBC
  uint64_t targetBytesPerPixel = 0;  // bytes per pixel of the path's screen targets (raster targets, depth, colour)
  // Bytes one depth-passing raster fragment writes: visbuf ID + depth, G-buffer targets + depth, forward colour +
  // depth.
  uint32_t rasterBytesPerFragment = 0;
  // With countOverdraw: depth-passing raster fragments per pixel (all pixels), and the bytes written per pixel =
  // fragments x rasterBytesPerFragment + the resolve's colour write (visbuf/G-buffer: 8 per covered pixel) + classified
  // shading's tile list and material records.
  // Clears are not counted. 0 without countOverdraw.
  double rasterWritesPerPixel = 0.0;
  double bytesWrittenPerPixel = 0.0;
};

// The colour of pixels that show nothing (linear RGBA; the colour image is cleared to it, then rounded to rgba16f).
inline constexpr float kBackgroundColor[4] = {0.10f, 0.12f, 0.15f, 1.0f};

struct FrameResult {
  uint32_t width = 0, height = 0;
  std::vector<float> color;     // RGBA, linear, row-major, top row first
  std::vector<uint32_t> ids;    // 2 per pixel: object ID + 1 (0 = nothing), triangle index in its LOD; visbuf
                                // MSAA: 2 per sample, [(pixel * samples + sample) * 2 + {0, 1}]
  std::vector<uint32_t> drawnObjects;  // with readDraws: object IDs drawn this frame (any order)
  std::vector<uint32_t> drawnLods;     // with readDraws: the LOD level of each drawn object (parallel)
  struct PyramidLevel {
    uint32_t width = 0, height = 0;  // valid size: ceil(frame size / 2^level)
    std::vector<float> depth;        // reverse-Z, row-major
  };
  std::vector<PyramidLevel> pyramid;   // with readPyramid: level 0 (full resolution) first
  std::vector<uint32_t> overdraw;      // with countOverdraw: depth-test-passing fragments per pixel
  // With readAttributes: ATTRIBUTE_FLOATS (shaders/shared/config.h) floats per pixel, all 0 where nothing was
  // drawn: camera-relative position, depth, normal, uv, barycentrics and their per-pixel derivatives.
  std::vector<float> attributes;
  FrameStats stats;
};

// record(): what the host runs and reads. The outputs are the renderer's own images, valid until the next
// record() or resize(); the host may read them (sampling, blits, copies) after these command buffers and before
// it submits the next frame's.
struct FrameImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;  // the layout the frame leaves it in
};
struct RecordedFrame {
  uint64_t index = 0;  // frames recorded before this one
  // Submit these in this order on the renderer's queue (gpu::Device::queue), in one vkQueueSubmit or in
  // consecutive ones, before any host command that reads the outputs. They are the renderer's, reused by the
  // frame index + framesInFlight. (One command buffer per pass: Mesa 22.3 lavapipe needs the split.)
  std::vector<VkCommandBuffer> commandBuffers;
  // Colour: rgba16f, linear. IDs: r32ui or rg32ui (IdEncoding; the visbuf path only, else null). Depth: D32,
  // reverse-Z. The last command buffer ends with a barrier that makes every write to them available and visible
  // to VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT / VK_ACCESS_2_MEMORY_READ_BIT in the layouts given here.
  FrameImage color, ids, depth;
  uint32_t width = 0, height = 0;
};
struct FrameInputs {
  Camera camera;
  FrameOptions options;  // read* and countOverdraw must be false: renderFrame reads back
  // The colour output's layout at the end of the frame: TRANSFER_SRC_OPTIMAL (blit or copy it),
  // SHADER_READ_ONLY_OPTIMAL (sample it) or GENERAL.
  VkImageLayout colorLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
};

// Errors: no method aborts or throws. A Vulkan call that fails inside one (out of memory, device lost, a driver
// error) comes back as its Error (ErrorCode::OutOfMemory, DeviceLost or VulkanError, naming the call, file and
// line) and leaves the renderer lost(): from then on every method that would touch the GPU returns an error, and the
// host destroys it (the destructor is safe) and creates another -- on a new gpu::Device after DeviceLost. create()
// failing leaves nothing behind. Logging goes through setLogSink (visbuf/core/log.h).
//
// Threads: a Renderer is used by one thread at a time (no method is safe to call concurrently with another on the
// same renderer, const ones included); the host serialises them. Renderers on one gpu::Device may be used from
// different threads only if the host also serialises their queue submissions (Vulkan's rule for one VkQueue):
// renderFrame and readSkinnedInstance submit to the device's queue, record() does not. The log sink may be
// called from any of those threads.
class Renderer {
 public:
  static Result<std::unique_ptr<Renderer>> create(gpu::Device& device, const Scene& scene,
                                                  const RendererConfig& config);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // True after a Vulkan failure inside one of its methods (see above): destroy it and create another.
  bool lost() const;

  // Recreates the screen targets (the ID encoding may change with the capacity, not the size).
  Status resize(uint32_t width, uint32_t height);
  Result<FrameResult> renderFrame(const Camera& camera, const FrameOptions& options);

  // Records frame `index` for the host to submit (RecordedFrame). Contract: before record() of frame n, the host
  // has waited (fence or timeline) for frame n - framesInFlight to finish; record() itself never waits, except
  // once for the device to go idle when a frame first needs a lazily created resource (MSAA targets, the
  // micro-raster buffer, classification). Decisions that feed back (skipping a useless pyramid or micro-raster)
  // use the newest completed frame's counters.
  Result<RecordedFrame> record(const FrameInputs& inputs);
  // The stats of the newest frame whose commands have finished (frame index - framesInFlight, read without
  // waiting when record() reuses its slot): counters and GPU pass times. Empty before that.
  const std::optional<FrameStats>& completedStats() const;

  // Scene changes, applied by the next frame recorded (renderFrame or record). Each call either applies all of
  // its changes or refuses all of them (InvalidArgument), naming the first bad one: an object that is not live, a
  // skinned or node-animated object (its pose or FrameOptions::animationTime places it), a non-finite or singular
  // transform; CapacityExceeded for a winding flip into a micro-raster draw list that is full (the winding picks
  // the draw list; RendererConfig::spareObjects gives every list room).
  Status setTransforms(std::span<const ObjectTransform> moves);
  Status setVisible(uint32_t object, bool visible);  // hidden objects are neither drawn nor tested
  // A new object in a free slot (RendererConfig::spareObjects, then slots freed by removeObject); its ID. Refused:
  // bad mesh or material, non-finite or singular transform, no free slot (CapacityExceeded).
  Result<uint32_t> addObject(const Object& object);
  Status removeObject(uint32_t object);  // frees its slot; skinned objects cannot be removed
  uint32_t objectSlots() const;          // scene objects + spare slots: object IDs are below this
  const Object* object(uint32_t id) const;  // the live object with that ID, else nullptr
  const IdEncoding& idEncoding() const;
  // Forgets which objects were visible last frame (as after a camera cut): costs time, never pixels.
  void clearHistory();
  // Reads skinned instance `instance` (Scene::skinnedObjects order) back: what the last frame's skinning wrote.
  // Fails for an index past the scene's skinned instances.
  Result<SkinnedInstanceReadback> readSkinnedInstance(uint32_t instance) const;

  struct Impl;

 private:
  explicit Renderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The FrameOptions::msaa values this device can render (ascending, always 1): counts among 2 and 4 that every
// multisampled target supports (r32ui / rg32ui IDs, D32 depth, rgba16f colour: attachment + sampled), with the
// standard sample locations. Lavapipe: 1, 4.
std::vector<uint32_t> supportedMsaaSamples(gpu::Device& device);

// Chooses the ID split for a draw capacity and the largest triangle count of one draw.
IdEncoding chooseIdEncoding(uint32_t drawCapacity, uint32_t maxTrianglesPerDraw, bool forceWide);

}  // namespace visbuf
