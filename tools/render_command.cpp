// visbuf render: one scene, one camera, headless; writes the image and prints per-pass GPU times and
// culling stats (also as JSON).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <fmt/format.h>

#include "cli_checks.h"
#include "commands.h"
#include "invocation.h"
#include "debug_views.h"
#include "visbuf/core/image_compare.h"
#include "visbuf/core/image_io.h"
#include "visbuf/gpu/device.h"
#include "visbuf/passes/depth_pyramid_pass.h"
#include "visbuf/render/pixel_judge.h"
#include "visbuf/render/renderer.h"
#include "visbuf/render/scene_motion.h"
#include "visbuf/scene/generate.h"
#include "render_budget.h"
#include "skin_check.h"
#include "stats_output.h"

namespace visbuf::tools {

void addRenderCommand(CLI::App& app, RenderCommand& c) {
  CLI::App* sub = app.add_subcommand("render", "render a scene headless to an image, print GPU times and stats");
  addSceneOptions(*sub, c.scene);
  addCameraOptions(*sub, c.camera);
  sub->add_option("--size", c.size, "image size WxH")->check(imageSize())->capture_default_str();
  sub->add_option("--path", c.path,
                  "visbuf | forward (CPU-culled, one draw per object reference) | gbuffer (visbuf's culling, deferred "
                  "G-buffer raster + lighting baseline; no IDs)")
      ->check(CLI::IsMember({"visbuf", "forward", "gbuffer"}))
      ->capture_default_str();
  sub->add_option("--device", c.device, "auto | cpu | gpu | N (auto prefers a GPU, else lavapipe)")->capture_default_str();
  sub->add_option("--cull", c.cull, "none | frustum | occlusion (two-phase, depth pyramid; forward path: frustum)")
      ->check(CLI::IsMember({"none", "frustum", "occlusion"}))
      ->capture_default_str();
  sub->add_option("--lod-error", c.lodError, "LOD threshold in pixels of projected error")
      ->check(finiteNumber(0.0, 1e6))
      ->capture_default_str();
  sub->add_flag("--no-lod", c.noLod, "always draw the full-detail mesh");
  sub->add_option("--draw-capacity", c.drawCapacity, "max draw commands per phase and draw list (default: one per object)")
      ->check(unsignedIn(1, UINT32_MAX));
  sub->add_flag("--wide-ids", c.wideIds, "force the 64-bit visibility target");
  sub->add_flag("--validation", c.validation, "enable Vulkan validation layers (any message fails the run)");
  sub->add_option("--time", c.time, "animation time in seconds (skinned scenes: every instance's pose)")
      ->check(finiteNumber(-1e9, 1e9))
      ->capture_default_str();
  sub->add_flag("--animate", c.animate, "with --frames N: advance the animation by 1/30 s per frame (else paused)");
  sub->add_option("--skin-bounds", c.skinBounds,
                  "culling bounds of skinned instances: joints (the joints' reach, CPU) | gpu (AABB of the skinned "
                  "vertices, reduced by the skinning pass)")
      ->check(CLI::IsMember({"joints", "gpu"}))
      ->capture_default_str();
  sub->add_option("--skin-check", c.skinCheck,
                  "after the frames, read N skinned instances back and report their error against the CPU's "
                  "double-precision skinning and whether their culling bounds contain them")
      ->check(unsignedIn(0, UINT32_MAX));
  sub->add_option("--frames", c.frames, "frames to render; timings are the median over frames after the first")
      ->check(unsignedIn(1, 10000))
      ->capture_default_str();
  sub->add_option("-o,--output", c.output, "colour image (.png, .exr, .tif); empty: none")->capture_default_str();
  sub->add_option("--ids-out", c.idsOut, "decoded IDs (object+1, triangle) as a 2-channel uint32 TIFF")
      ->check(nonEmptyPath());
  sub->add_option("--json", c.json, "write the stats as JSON")->check(nonEmptyPath());
  sub->add_flag("--reference", c.reference,
                "also render the forward path (same culling and LOD rule, hardware interpolation) over the same "
                "frames and report the error against it beside both times");
  sub->add_flag("--reference-full", c.referenceFull,
                "also render visbuf with no culling and no LOD (the exact image) and report the error of this "
                "configuration against it: what LOD and culling cost");
  sub->add_option("--view", c.view, "image written to -o: shaded | objects | triangles | lod | culled | pyramid | overdraw")
      ->check(CLI::IsMember(debugViewNames()))
      ->capture_default_str();
  sub->add_option("--pyramid-level", c.pyramidLevel, "--view pyramid: depth pyramid level (0 = full resolution)")
      ->check(integerIn(0, 14));
  sub->add_flag("--reference-lights", c.referenceLights,
                "also render the same frame shading every pixel with every point light (no tile lists) and report "
                "the error against it");
  sub->add_option("--judge", c.judge,
                  "also render the frame with both paths (visbuf and forward, same camera, culling and LOD rule), judge "
                  "every pixel against the exact colour computed in double precision on the CPU, print a summary "
                  "(and put it in the JSON) and write a heat map here (.png, .exr, .tif: red = the visbuf path's error, "
                  "green = the forward path's, log scale 1e-5..1e-1; blue: not judged: skinned objects); with --msaa "
                  "N the exact colour is the mean of the exact colours at the N sample locations; "
                  "not with --path gbuffer, --moving, --churn or --freeze-culling");
  sub->add_flag("--all-lights", c.allLights, "shade every pixel with every point light (no light cull pass)");
  sub->add_option("--msaa", c.msaa,
                  "samples per pixel: 1, 2 or 4 (the device's supported counts; visbuf: per-sample shading where a "
                  "pixel's samples differ, forward: hardware resolve; not with gbuffer, BLEND scenes, --view or "
                  "--ids-out)")
      ->check(CLI::IsMember({"1", "2", "4"}))
      ->capture_default_str();
  sub->add_option("--shading", c.shading,
                  "visbuf shading: auto (the device type's default: covered on a CPU device, uber on a GPU; a CPU "
                  "device takes uber too once a frame shows something in 65 % of its pixels, until one shows less "
                  "than 55 %) | uber (one "
                  "dispatch over every pixel) | covered (one workgroup per 8x8 tile that shows anything) | classified "
                  "(per-material tile lists, one indirect dispatch per material); MSAA frames: uber")
      ->check(CLI::IsMember({"auto", "uber", "covered", "classified"}))
      ->capture_default_str();
  sub->add_option("--sw-raster", c.swRaster,
                  "software micro-raster (auto: on; on a GPU only while it takes >= 262,144 triangles, as measured): objects whose screen box is at most --sw-raster-px per side are "
                  "rasterised in compute and merged into the same ID target (visbuf, single-sampled, opaque lists)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  sub->add_option("--sw-raster-px", c.swRasterPixels, "--sw-raster: the object size bound in pixels (0, 94]; default 94 on a CPU device, 64 on a GPU")
      ->check(finiteNumber(0.0, 94.0, true, false))
      ->capture_default_str();
  sub->add_option("--sw-raster-area", c.swRasterArea,
                  fmt::format("--sw-raster: the bound on an object's (or cluster's) screen box area per triangle in "
                              "pixels (0, {}]; default {}",
                              kMaxSwRasterArea, kDefaultSwRasterArea))
      ->check(finiteNumber(0.0, kMaxSwRasterArea, true, false))
      ->capture_default_str();
  sub->add_option("--sw-resolve", c.swResolve,
                  "where the micro-raster's fragments meet the raster's: merge (into the ID target and depth) | shading "
                  "(the pyramid and the shading take the nearer per pixel; frames that read IDs, cull lights or draw "
                  "transparency merge anyway) | auto (shading)")
      ->check(CLI::IsMember({"auto", "merge", "shading"}))
      ->capture_default_str();
  sub->add_flag("--no-clusters", c.noClusters,
                "draw every hardware-raster object whole (default: as its clusters that survive the frustum, their "
                "back-face cone and the depth pyramid)");
  sub->add_flag("--no-early-cluster-occlusion", c.noEarlyClusterOcclusion,
                "occlusion culling with clusters: draw every front-facing cluster of last frame's visible objects in "
                "the early phase (default: defer the ones last frame's depth pyramid hides to a retest in the late "
                "phase; the image is the same)");
  sub->add_flag("--always-pyramid", c.alwaysPyramid,
                "occlusion culling: build the depth pyramid every frame (default: a pyramid that hid nothing, or "
                "objects worth less than half its GPU time in raster, is skipped for 16 frames, then built again; "
                "the image is the same)");
  sub->add_option("--moving", c.moving,
                  "every frame, move this fraction of the objects (not skinned or node-animated) along deterministic "
                  "closed paths through the renderer's scene-update API; the JSON gets per-frame uploaded bytes and "
                  "culling counters (use with --frames)")
      ->check(finiteNumber(0.0, 1.0))
      ->capture_default_str();
  sub->add_option("--churn", c.churn,
                  "every frame, remove, add and hide this fraction of the objects (at least one each; hidden ones "
                  "reappear 3 frames later)")
      ->check(finiteNumber(0.0, 0.5))
      ->capture_default_str();
  sub->add_flag("--freeze-culling", c.freezeCulling,
                "cull from the scene's default camera, then render from --camera-pos/--camera-target with that "
                "frame's draw lists (shows what the first camera culled)");
}

namespace {
int fail(const Error& e) {
  // Messages quote names and paths from assets: escaped (the device report alone keeps its lines).
  std::fprintf(stderr, "visbuf: error (%s): %s\n", errorCodeName(e.code),
               printable(e.message, e.code == ErrorCode::NoDevice).c_str());
  return 1;
}

// Options that contradict each other: a usage error (exit 2).
int usage(const std::string& message) {
  std::fprintf(stderr, "visbuf render: %s (see visbuf render --help)\n", printable(message).c_str());
  return 2;
}
// An option value out of its range (for the image size too): bad input (exit 1), as CLI11's validators give.
int badValue(const std::string& message) {
  std::fprintf(stderr, "visbuf render: %s (see visbuf render --help)\n", printable(message).c_str());
  return 1;
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return ext;
}

// The objects --objects asks for (or the generated layout's default), before the scene exists; 0 when only
// loading the file tells (estimateUpload checks those once loaded).
uint64_t expectedObjects(const SceneOptions& o) {
  if (o.objects > 0) return o.objects;
  if (o.scene == "field") return FieldParams{}.objects;
  if (o.scene == "city") return CityParams{}.objects;
  if (o.scene == "foliage" || o.scene == "foliage-opaque") return FoliageParams{}.cards;
  if (o.scene == "terrain") return 1;
  return 0;
}
// --judge: the frame rendered by both paths with IDs and the drawn LODs, judged pixel by pixel against the exact
// colour (pixel_judge.h); writes the heat map, prints the summary and returns it for the JSON.
Result<nlohmann::json> judgeFrame(Renderer& renderer, const Scene& scene, const Camera& camera, FrameOptions fo,
                                  double time, const std::string& heatMapPath) {
  fo.readColor = fo.readIds = fo.readDraws = true;
  fo.animationTime = time;
  fo.path = RenderPath::Visbuf;
  Result<FrameResult> vis = renderer.renderFrame(camera, fo);
  if (!vis) return vis.error();
  fo.path = RenderPath::Forward;
  fo.readIds = fo.msaa == 1;  // (a multisampled forward frame has no ID variant: the MSAA judge reads visbuf's)
  Result<FrameResult> fwd = renderer.renderFrame(camera, fo);
  if (!fwd) return fwd.error();
  Result<PixelJudgement> j = fo.msaa > 1 ? judgeMsaaPixels(scene, camera, *vis, *fwd, fo.msaa, {.animationTime = time})
                                         : judgePixels(scene, camera, *vis, *fwd, {.animationTime = time});
  if (!j) return j.error();
  if (Status s = writeColorImage(heatMapPath, j->width, j->height, j->heatMap); !s) return s.error();
  auto accuracy = [](const PathAccuracy& a) {
    return nlohmann::json{{"maxAbs", a.maxAbs},
                          {"maxBeyondRounding", a.maxBeyondRounding},
                          {"meanAbs", a.meanAbs},
                          {"psnr", std::isfinite(a.psnr) ? a.psnr : 999.0},
                          {"pixelsOver8Bit", a.over8Bit}};
  };
  for (const auto& [name, a] : {std::pair{"visbuf", &j->visbuf}, std::pair{"forward", &j->forward}})
    std::printf("judge         %-7s vs exact: max %.2e (%.2e beyond rgba16f rounding), mean %.2e, PSNR %.1f dB, %zu "
                "pixels > 1/255\n",
                name, a->maxAbs, a->maxBeyondRounding, a->meanAbs, a->psnr, a->over8Bit);
  std::printf("judge         %zu covered pixels, %zu judged (not judged: %zu skinned, %zu parallel rays); %zu %s\n",
              j->covered, j->judged, j->notJudgedSkinned, j->notJudgedParallel, j->coverageMismatch,
              fo.msaa > 1 ? "edge pixels (samples showing different triangles; the exact colour: the mean over the "
                            "sample locations)"
                          : "show different triangles in the two paths");
  std::printf("judge         %zu judged pixels differ: visbuf closer at %zu (by %.1e mean, %.1e max), forward "
              "closer at %zu (by %.1e mean, %.1e max), %zu ties\n",
              j->differing, j->visbufCloser, j->visbufMargin, j->visbufMaxMargin, j->forwardCloser, j->forwardMargin,
              j->forwardMaxMargin, j->ties);
  std::printf("heat map      %s\n", printable(heatMapPath).c_str());
  return nlohmann::json{{"covered", j->covered},
                        {"judged", j->judged},
                        {"notJudged", {{"skinned", j->notJudgedSkinned},
                                       {"parallel", j->notJudgedParallel}}},
                        {"coverageMismatch", j->coverageMismatch},
                        {"visbuf", accuracy(j->visbuf)},
                        {"forward", accuracy(j->forward)},
                        {"differing", j->differing},
                        {"visbufCloser", j->visbufCloser},
                        {"forwardCloser", j->forwardCloser},
                        {"ties", j->ties},
                        {"visbufMargin", {{"mean", j->visbufMargin}, {"max", j->visbufMaxMargin}}},
                        {"forwardMargin", {{"mean", j->forwardMargin}, {"max", j->forwardMaxMargin}}},
                        {"heatMap", heatMapPath}};
}
}  // namespace

int runRender(const RenderCommand& c) {
  // Every option and output path is checked before any work (values out of range were already refused by
  // the option validators, exit 2): combinations are usage errors (2), paths and memory bad input (1).
  auto size = parseSize(c.size);
  if (!size) return badValue(size.error().message);
  auto devOptions = gpu::parseDeviceOption(c.device, {.validation = c.validation});
  if (!devOptions) return fail(devOptions.error());
  if (!(c.lodError >= 0.0f)) return badValue("--lod-error must be >= 0");
  if (c.msaa > 1 && (c.view != "shaded" || !c.idsOut.empty()))
    return usage("--view and --ids-out show one ID per pixel: use them with --msaa 1");
  if (int(c.reference) + int(c.referenceFull) + int(c.referenceLights) > 1)
    return usage("--reference, --reference-full and --reference-lights are exclusive");
  if (c.freezeCulling && c.path == "forward") return usage("--freeze-culling needs --path visbuf or gbuffer");
  const bool moving = c.moving > 0.0 || c.churn > 0.0;
  if (!c.judge.empty()) {
    if (c.path == "gbuffer")
      return usage("--judge needs the triangle IDs of the visbuf and forward paths: not --path gbuffer");
    if (moving || c.freezeCulling)
      return usage("--judge renders the scene as it is from the camera: not with --moving, --churn or "
                   "--freeze-culling");
  }
  if (moving && (c.reference || c.referenceFull || c.referenceLights))
    return usage("--moving and --churn change the scene every frame: the --reference options compare one fixed scene");
  if (moving && c.freezeCulling) return usage("--moving and --churn do not combine with --freeze-culling");
  if (const uint32_t levels = passes::pyramidLevelCount(size->first, size->second);
      c.pyramidLevel >= 0 && uint32_t(c.pyramidLevel) >= levels)
    return badValue(fmt::format("--pyramid-level {}: a {}x{} frame's depth pyramid has levels 0..{}", c.pyramidLevel,
                             size->first, size->second, levels - 1));
  // Every output, before any work (bad input, exit 1): a writable folder, not an input named on the command line,
  // no two in one file; again once the scene is loaded (its buffers, images and packs are inputs too).
  std::vector<OutputFile> outputs;
  if (!c.output.empty()) outputs.push_back({"-o", c.output});
  if (!c.idsOut.empty()) outputs.push_back({"--ids-out", c.idsOut});
  if (!c.judge.empty()) outputs.push_back({"--judge", c.judge});
  if (!c.json.empty()) outputs.push_back({"--json", c.json});
  noteSceneInputs(c.scene);
  if (Status s = checkOutputs(outputs); !s) return fail(s.error());
  if (!c.output.empty()) {
    const std::string ext = lowerExtension(c.output);
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg" && ext != ".exr" && ext != ".tif" && ext != ".tiff")
      return fail({ErrorCode::InvalidArgument,
                   fmt::format("-o '{}': the image must be .png, .jpg, .exr or .tif", c.output)});
  }
  if (!c.idsOut.empty()) {
    const std::string ext = lowerExtension(c.idsOut);
    if (ext != ".tif" && ext != ".tiff")
      return fail({ErrorCode::InvalidArgument, fmt::format("--ids-out '{}': the ID image must be .tif", c.idsOut)});
  }
  if (!c.judge.empty()) {
    const std::string ext = lowerExtension(c.judge);
    if (ext != ".png" && ext != ".exr" && ext != ".tif" && ext != ".tiff")
      return fail({ErrorCode::InvalidArgument,
                   fmt::format("--judge '{}': the heat map must be .png, .exr or .tif", c.judge)});
  }

  // Memory, before anything is allocated: the machine's for --objects and the targets, then the device's
  // (the device is created before the scene so that its heaps are known), then, once the scene is loaded,
  // what uploading it adds.
  RenderBudgetInput budget;
  budget.objects = expectedObjects(c.scene);
  budget.lights = c.scene.lights;
  budget.materials = c.scene.materials;
  budget.width = size->first;
  budget.height = size->second;
  budget.msaa = c.msaa;
  budget.gbuffer = c.path == "gbuffer";
  budget.ids = !c.idsOut.empty();
  budget.reference = c.reference || c.referenceFull || c.referenceLights || !c.judge.empty();
  budget.debugView = c.view != "shaded";
  const std::string asked = c.scene.objects > 0
                                ? fmt::format("--objects {} at {}x{}", c.scene.objects, size->first, size->second)
                                : fmt::format("--scene {} at {}x{}", c.scene.scene, size->first, size->second);
  if (Status s = checkMemory(estimateRender(budget), nullptr, asked); !s) return fail(s.error());
  auto device = gpu::Device::create(*devOptions);
  if (!device) return fail(device.error());
  if (Status s = checkMemory(estimateRender(budget), device->get(), asked); !s) return fail(s.error());
  // uploadScene's limit: the objects' records in two descriptor windows of maxStorageBufferRange. A file's copies
  // (--objects N on a glTF or a pack) are checked against it once the file tells its objects, before any copy.
  SceneOptions sceneOptions = c.scene;
  {
    const uint64_t range = (*device)->properties().limits.maxStorageBufferRange;
    const uint64_t maxObjects = 2 * (range / sizeof(gpu::ObjectData) / 4 * 4);
    if (budget.objects > maxObjects)
      return fail({ErrorCode::CapacityExceeded,
                   fmt::format("{}: {} objects are over the {} this device can address ({} bytes each in two "
                               "windows of maxStorageBufferRange {})",
                               asked, budget.objects, maxObjects, sizeof(gpu::ObjectData), range)});
    sceneOptions.load.maxObjects = maxObjects;
  }

  auto scene = loadScene(sceneOptions);
  if (!scene) return fail(scene.error());
  if (Status s = checkOutputs(outputs); !s) return fail(s.error());
  if (Status s = checkMemory(estimateUpload(*scene, budget), device->get(), fmt::format("uploading this scene ({} "
                                                                                         "objects) at {}x{}",
                                                                                         scene->objects.size(),
                                                                                         size->first, size->second));
      !s)
    return fail(s.error());
  if (camerasListRequested(c.camera)) {
    std::fputs(describeCameras(*scene).c_str(), stdout);
    return 0;
  }
  auto camera = makeCamera(c.camera, *scene);
  if (!camera) return fail(camera.error());

  std::optional<SceneMotion> motion;
  if (moving) {
    auto m = SceneMotion::create(*scene, {.moving = c.moving, .churn = c.churn, .seed = 1});
    if (!m) return fail(m.error());
    motion.emplace(std::move(m.value()));
  }
  RendererConfig rc;
  rc.spareObjects = motion ? motion->spareObjects() : 0;
  rc.width = size->first;
  rc.height = size->second;
  rc.drawCapacity = c.drawCapacity;
  rc.forceWideIds = c.wideIds;
  rc.skinBounds = c.skinBounds == "gpu" ? SkinBounds::Gpu : SkinBounds::Joints;
  auto renderer = Renderer::create(**device, *scene, rc);
  if (!renderer) return fail(renderer.error());

  FrameOptions fo;
  fo.path = c.path == "forward"   ? RenderPath::Forward
            : c.path == "gbuffer" ? RenderPath::GBuffer
                                  : RenderPath::Visbuf;
  fo.cull = c.cull == "none" ? CullMode::None : c.cull == "frustum" ? CullMode::Frustum : CullMode::Occlusion;
  fo.lodErrorPixels = c.noLod ? 0.0f : c.lodError;
  fo.tiledLights = !c.allLights;
  fo.msaa = c.msaa;
  fo.shading = parseShadingMode(c.shading);
  fo.swRaster = parseSwRasterMode(c.swRaster);
  fo.swRasterPixels = c.swRasterPixels;
  fo.swRasterArea = c.swRasterArea;
  fo.clusters = !c.noClusters;
  fo.swResolve = parseSwResolve(c.swResolve);
  fo.earlyClusterOcclusion = !c.noEarlyClusterOcclusion;
  fo.skipUselessPyramid = !c.alwaysPyramid;
  // Renders c.frames frames; the returned stats hold medians over the frames after the first (warm-up).
  // --moving / --churn: the scene changes before every frame; perFrame gets each frame's changes and counters.
  nlohmann::json perFrame = nlohmann::json::array();
  Status motionStatus;
  auto run = [&](FrameOptions options, bool readColor, Result<FrameResult>& frame) -> FrameStats {
    std::vector<FrameStats> runs;
    for (uint32_t i = 0; i < c.frames; ++i) {
      SceneMotionFrame changed;
      if (motion) {
        auto m = motion->apply(**renderer, i);
        if (!m) {
          motionStatus = m.error();
          return {};
        }
        changed = *m;
      }
      const bool last = i + 1 == c.frames;
      options.readColor = last && readColor;
      options.readIds = last && !c.idsOut.empty();
      options.readDraws = false;
      options.readPyramid = false;
      if (last && c.view != "shaded" && (options.path == RenderPath::Visbuf || c.view == "overdraw"))
        prepareViewOptions(c.view, options);
      options.animationTime = c.time + (c.animate ? double(i) / 30.0 : 0.0);  // --animate: 30 poses a second
      frame = (*renderer)->renderFrame(*camera, options);
      if (!frame) return {};
      runs.push_back(frame->stats);
      if (motion) perFrame.push_back(motionFrameJson(changed, frame->stats));
    }
    FrameStats stats = frame->stats;
    if (runs.size() > 1) {
      auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v[v.size() / 2];
      };
      for (size_t p = 0; p < stats.graph.passMs.size(); ++p) {
        std::vector<double> v;
        for (size_t r = 1; r < runs.size(); ++r) v.push_back(runs[r].graph.passMs[p].second);
        stats.graph.passMs[p].second = median(v);
      }
      std::vector<double> g, cpu, wall;
      for (size_t r = 1; r < runs.size(); ++r) {
        g.push_back(runs[r].gpuMs);
        cpu.push_back(runs[r].cpuRecordMs);
        wall.push_back(runs[r].wallMs);
      }
      stats.gpuMs = median(g);
      stats.cpuRecordMs = median(cpu);
      stats.wallMs = median(wall);
    }
    return stats;
  };
  const bool compare = (c.reference || c.referenceFull || c.referenceLights) && fo.path != RenderPath::Forward;
  if (int(c.reference) + int(c.referenceFull) + int(c.referenceLights) > 1)
    return fail({ErrorCode::InvalidArgument, "--reference, --reference-full and --reference-lights are exclusive"});
  if (c.freezeCulling) {
    if (fo.path == RenderPath::Forward)
      return fail({ErrorCode::InvalidArgument, "--freeze-culling needs --path visbuf or gbuffer"});
    FrameOptions cullFrame = fo;
    cullFrame.readColor = false;
    for (int i = 0; i < 3; ++i) {  // occlusion mode's history settles after two frames
      auto f = (*renderer)->renderFrame(scene->defaultCamera, cullFrame);
      if (!f) return fail(f.error());
    }
    fo.freezeCulling = true;
  }
  Result<FrameResult> frame = makeError(ErrorCode::InvalidArgument, "no frame");
  FrameStats stats = run(fo, !c.output.empty() || compare, frame);
  if (!motionStatus) return fail(motionStatus.error());
  if (!frame) return fail(frame.error());

  uint64_t sceneTriangles = 0;
  for (const Object& o : scene->objects) sceneTriangles += scene->meshes[o.mesh].triangleCount();
  std::printf("scene         %s: %zu objects, %zu meshes, %zu materials, %llu triangles at full detail\n",
              printable(c.scene.scene).c_str(), scene->objects.size(), scene->meshes.size(), scene->materials.size(),
              (unsigned long long)sceneTriangles);
  std::printf("%s", formatStats(stats).c_str());
  if (c.frames > 1) std::printf("(times: median of %u frames after 1 warm-up)\n", c.frames - 1);
  if (motion) std::printf("%s", formatMotion(perFrame, motion->movingObjects()).c_str());
  if (!c.output.empty() && c.view != "shaded") {
    auto view = buildDebugView(c.view, *frame, *scene, *camera, std::max(c.pyramidLevel, 0));
    if (!view) return fail(view.error());
    frame->color = std::move(view.value());
  }
  if (!c.output.empty()) {
    Status s = writeColorImage(c.output, frame->width, frame->height, frame->color);
    if (!s) return fail(s.error());
    std::printf("image         %s\n", printable(c.output).c_str());
  }
  if (!c.idsOut.empty()) {
    Status s = writeIdImage(c.idsOut, frame->width, frame->height, frame->ids);
    if (!s) return fail(s.error());
    std::printf("ids           %s\n", printable(c.idsOut).c_str());
  }
  nlohmann::json referenceJson;
  if (compare) {
    FrameOptions ref = fo;
    if (c.referenceFull) {
      ref.cull = CullMode::None;
      ref.lodErrorPixels = 0.0f;
      ref.tiledLights = false;
    } else if (c.referenceLights) {
      ref.tiledLights = false;
    } else {
      ref.path = RenderPath::Forward;
    }
    const char* refName = c.referenceFull     ? "full (no culling, no LOD, every light)"
                          : c.referenceLights ? "all lights (no tiles)"
                                              : "forward";
    Result<FrameResult> refFrame = makeError(ErrorCode::InvalidArgument, "no frame");
    FrameStats refStats = run(ref, true, refFrame);
    if (!refFrame) return fail(refFrame.error());
    ImageError e = compareColor(frame->color, refFrame->color);
    const double refMs = refStats.gpuMs + refStats.cpuRecordMs, visMs = stats.gpuMs + stats.cpuRecordMs;
    std::printf("reference     %s: gpu %.3f ms + cpu %.3f ms (this %.3f ms; reference/this = %.2f)\n", refName,
                refStats.gpuMs, refStats.cpuRecordMs, visMs, refMs / std::max(visMs, 1e-9));
    std::printf("error         vs %s: max %.5f, mean %.6f, PSNR %.1f dB, %.4f%% pixels > 1/255\n", refName, e.maxAbs,
                e.meanAbs, e.psnr, 100.0 * e.differingFraction);
    referenceJson = statsToJson(refStats);
    referenceJson["kind"] = c.referenceFull ? "full" : c.referenceLights ? "lights" : "forward";
    referenceJson["error"] = {{"maxAbs", e.maxAbs},
                              {"meanAbs", e.meanAbs},
                              {"psnr", std::isfinite(e.psnr) ? e.psnr : 999.0},
                              {"differingFraction", e.differingFraction}};
  }
  nlohmann::json judgeJson;
  if (!c.judge.empty()) {
    const double lastTime = c.time + (c.animate ? double(c.frames - 1) / 30.0 : 0.0);  // run()'s last frame
    auto judged = judgeFrame(**renderer, *scene, *camera, fo, lastTime, c.judge);
    if (!judged) return fail(judged.error());
    judgeJson = std::move(judged.value());
  }
  nlohmann::json skinJson;
  if (c.skinCheck > 0 && !scene->skinnedObjects.empty()) {
    const double lastTime = c.time + (c.animate ? double(c.frames - 1) / 30.0 : 0.0);  // run()'s last frame
    const SkinCheck k = checkSkinning(**renderer, *scene, lastTime, c.skinCheck);
    std::printf("skin check    %u instances, %llu vertices vs CPU double: position %.2e of the radius, normal %.2e, "
                "tangent %.2e; %llu outside their bounds; radius / tightest %.3f\n",
                k.instances, (unsigned long long)k.vertices, k.maxPositionError, k.maxNormalError, k.maxTangentError,
                (unsigned long long)k.outside, k.meanRadiusRatio);
    skinJson = skinCheckToJson(k);
  }
  if (!c.json.empty()) {
    nlohmann::json j = statsToJson(stats);
    stampInvocation(j, stats.device);
    if (compare) j["reference"] = referenceJson;
    if (!skinJson.is_null()) j["skinCheck"] = skinJson;
    if (!judgeJson.is_null()) j["judge"] = judgeJson;
    j["scene"] = c.scene.scene;
    j["frames"] = c.frames;
    j["lodErrorPixels"] = fo.lodErrorPixels;
    j["cull"] = c.cull;
    if (motion) {
      j["moving"] = c.moving;
      j["churn"] = c.churn;
      j["perFrame"] = perFrame;
    }
    Status s = writeJsonFile(c.json, j);
    if (!s) return fail(s.error());
  }
  if ((*device)->validationEnabled() && (*device)->validationMessages() > 0) {
    std::fprintf(stderr, "visbuf: %u validation message(s)\n", (*device)->validationMessages());
    return 3;
  }
  if (stats.cull.drawOverflow > 0) std::fprintf(stderr, "visbuf: warning: draw capacity overflow (%u dropped)\n", stats.cull.drawOverflow);
  return 0;
}

}  // namespace visbuf::tools
