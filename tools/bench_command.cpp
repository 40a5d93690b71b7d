// visbuf bench: run time against error. One scene per object count, a deterministic camera path, and the
// matrix path x cull x LOD rendered in one process on one device (one Renderer per scene size, the
// occlusion history cleared between configurations). Every configuration's measured frames are compared
// with a reference rendered once per camera of the path (forward path, no culling, no LOD; visbuf with no
// culling and no LOD when that would draw too many triangles). Writes bench.json, bench.csv, bench.md and
// bench.svg (time-vs-PSNR plot with the Pareto front) to the output folder, each atomically
// (tools/bench_report.cpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <unistd.h>

#include "bench_common.h"
#include "bench_in_flight.h"
#include "bench_report.h"
#include "cli_checks.h"
#include "commands.h"
#include "render_budget.h"
#include "visbuf/core/image_compare.h"
#include "visbuf/core/image_io.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "invocation.h"

namespace visbuf::tools {

void addBenchCommand(CLI::App& app, BenchCommand& c, int argc, char** argv) {
  for (int i = 0; i < argc; ++i) c.commandLine += (i ? " " : "") + shellQuote(argv[i]);
  CLI::App* sub = app.add_subcommand(
      "bench", "time against error: a camera path through a matrix of path x culling x LOD, per scene size");
  sub->add_option("--scene", c.scene, "field | city | a .gltf/.glb file | a baked pack (.vbp)")
      ->check(nonEmptyPath())
      ->capture_default_str();
  sub->add_option("--objects", c.objects,
                  "object counts, one scene each (default: 100,1000 for field and city; a file's own objects)")
      ->delimiter(',')
      ->check(unsignedIn(1, UINT32_MAX));
  sub->add_option("--seed", c.seed, "scene generator seed")->check(unsignedIn(0, UINT64_MAX))->capture_default_str();
  sub->add_option("--mesh", c.mesh, "field: .gltf/.glb mesh to instance (default: procedural torus knot)")
      ->check(nonEmptyPath());
  sub->add_option("--lights", c.lights, "scatter N point lights over each scene (tiled light culling)")
      ->check(unsignedIn(0, UINT32_MAX));
  sub->add_option("--size", c.size, "image size WxH")->check(imageSize())->capture_default_str();
  sub->add_option("--frames", c.frames, "measured frames per configuration (one camera of the path each)")
      ->check(unsignedIn(1, 10000))
      ->capture_default_str();
  sub->add_option("--warmup", c.warmup, "warm-up frames before them (the path's preceding cameras)")
      ->check(unsignedIn(0, 10000))
      ->capture_default_str();
  sub->add_option("--device", c.device, "auto | cpu | gpu | N")->capture_default_str();
  sub->add_option("--paths", c.paths, "render paths: visbuf,forward,gbuffer (G-buffer deferred baseline)")
      ->delimiter(',')
      ->check(CLI::IsMember({"visbuf", "forward", "gbuffer"}));
  sub->add_option("--cull", c.cull, "culling modes: none,frustum,occlusion (forward: no occlusion, skipped)")
      ->delimiter(',')
      ->check(CLI::IsMember({"none", "frustum", "occlusion"}));
  sub->add_option("--ids", c.ids, "visbuf ID target: auto (32 bits where they fit), wide (64 bits forced)")
      ->delimiter(',')
      ->check(CLI::IsMember({"auto", "wide"}));
  sub->add_option("--shading", c.shading,
                  "visbuf shading: auto (the device type's default), uber (one dispatch over every pixel), covered "
                  "(over the tiles that show anything), classified (per-material tile lists and dispatches)")
      ->delimiter(',')
      ->check(CLI::IsMember({"auto", "uber", "covered", "classified"}));
  sub->add_option("--sw-raster", c.swRaster,
                  "visbuf software micro-raster of small objects: auto (the device type's default), on, off (the "
                  "references always use the hardware raster)")
      ->delimiter(',')
      ->check(CLI::IsMember({"auto", "on", "off"}));
  sub->add_option("--materials", c.materials, "field, city, foliage: N generated PBR materials (3 of 4 textured)")
      ->check(unsignedIn(0, UINT32_MAX));
  sub->add_option("--vertices", c.vertices, "vertex precision: float, quantized (as bake --quantize stores them)")
      ->delimiter(',')
      ->check(CLI::IsMember({"float", "quantized"}));
  sub->add_option("--msaa", c.msaa,
                  "samples per pixel: 1,2,4 (each count against a reference at the same count; unsupported counts "
                  "and paths fail with the device's supported ones)")
      ->delimiter(',')
      ->check(CLI::IsMember({"1", "2", "4"}));
  sub->add_option("--lod", c.lod, "LOD thresholds in pixels of projected error; off = full detail")
      ->delimiter(',')
      ->check(CLI::Validator(
          [range = finiteNumber(0.0, 1e6)](std::string& text) -> std::string {
            if (text == "off") return {};
            const std::string e = range(text);
            return e.empty() ? e : "must be off or " + e.substr(std::string("must be ").size());
          },
          "off or a threshold in px"));
  sub->add_option("--reference", c.reference,
                  "auto (forward with no culling and no LOD unless the scene has more than --reference-max-triangles "
                  "triangles, then visbuf with no culling and no LOD) | forward | visbuf-full")
      ->check(CLI::IsMember({"auto", "forward", "visbuf-full"}))
      ->capture_default_str();
  sub->add_option("--reference-max-triangles", c.referenceMaxTriangles,
                  "--reference auto: full-detail triangles above which the forward reference is too slow")
      ->check(unsignedIn(0, UINT64_MAX))
      ->capture_default_str();
  sub->add_option("--in-flight", c.inFlight,
                  "instead of the matrix: steady-state throughput of Renderer::record with K frames in flight against "
                  "renderFrame (record, submit, wait), 5 % of the objects moving, the ratio per interleaved pair")
      ->delimiter(',')
      ->check(unsignedIn(1, 4));
  sub->add_option("--pairs", c.pairs, "--in-flight: interleaved pairs of runs")->check(unsignedIn(1, 100))->capture_default_str();
  sub->add_flag("--validation", c.validation, "enable Vulkan validation layers (any message fails the run)");
  sub->add_option("-o,--output", c.output, "output folder (bench.json, bench.csv, bench.md, bench.svg)")
      ->capture_default_str();
}

// ---- statistics -----------------------------------------------------------------------------------------

namespace {

double p95(std::vector<double> v) {  // nearest rank
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t rank = size_t(std::ceil(0.95 * double(v.size())));
  return v[std::clamp<size_t>(rank, 1, v.size()) - 1];
}

std::string lodText(float lod) { return lod > 0 ? fmt::format("{:g}", lod) : std::string("off"); }

}  // namespace

// The scene of one object count.
static SceneOptions sceneOptions(const BenchCommand& c, uint32_t objects) {
  SceneOptions so;
  so.scene = c.scene;
  so.objects = objects;
  so.seed = c.seed;
  so.mesh = c.mesh;
  so.lights = c.lights;
  so.materials = c.materials;
  return so;
}

namespace {

// ---- the configuration matrix ---------------------------------------------------------------------------

// path x cull x MSAA x LOD x IDs x vertices x shading x micro-raster. A path/cull pair that would repeat another
// goes to `skipped` with the reason; the visbuf-only dimensions are not varied for the other paths.
Result<std::vector<BenchConfig>> configMatrix(const BenchCommand& c, nlohmann::json& skipped) {
  std::vector<float> lods;
  for (const std::string& s : c.lod) {
    if (s == "off") {
      lods.push_back(0.0f);
      continue;
    }
    char* end = nullptr;
    const float v = std::strtof(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0f)
      return Error{ErrorCode::InvalidArgument, fmt::format("--lod '{}': expected off or a threshold >= 0 px", s)};
    lods.push_back(v);
  }
  std::vector<BenchConfig> configs;
  for (const std::string& p : c.paths)
    for (const std::string& cu : c.cull) {
      const RenderPath path = p == "forward"   ? RenderPath::Forward
                              : p == "gbuffer" ? RenderPath::GBuffer
                                               : RenderPath::Visbuf;
      const CullMode cull = cu == "none" ? CullMode::None : cu == "frustum" ? CullMode::Frustum : CullMode::Occlusion;
      if (path == RenderPath::Forward && cull == CullMode::Occlusion) {
        skipped.push_back({{"path", p}, {"cull", cu},
                           {"reason", "the forward path culls on the CPU by frustum only (would repeat frustum)"}});
        continue;
      }
      for (uint32_t m : c.msaa)
        for (float l : lods)
          for (const std::string& ids : c.ids)
            for (const std::string& v : c.vertices)
              for (const std::string& sh : c.shading)
                for (const std::string& sw : c.swRaster) {
                  if (path != RenderPath::Visbuf &&
                      (ids != c.ids.front() || sh != c.shading.front() || sw != c.swRaster.front()))
                    continue;  // no ID target, shading pass or micro-raster to vary
                  configs.push_back({path, cull, l, lodText(l), path == RenderPath::Visbuf && ids == "wide",
                                     v == "quantized", m, parseShadingMode(sh), parseSwRasterMode(sw)});
                }
    }
  if (configs.empty()) return Error{ErrorCode::InvalidArgument, "no configuration left to run"};
  return configs;
}

// ---- one scene size -------------------------------------------------------------------------------------

// The renderers of the other precision variants of a scene: 64-bit IDs forced (--ids wide), quantised vertices
// (--vertices quantized: the scene through an in-memory pack written with quantisation and read back). The
// quantised scene is kept beside the renderers drawing it.
struct PrecisionVariants {
  std::unique_ptr<Scene> quantizedScene;
  std::map<std::pair<bool, bool>, std::unique_ptr<Renderer>> renderers;  // (wide IDs, quantised) -> renderer
};

Status createVariants(gpu::Device& device, const Scene& scene, const RendererConfig& rc,
                      const std::vector<BenchConfig>& configs, PrecisionVariants& variants) {
  if (std::any_of(configs.begin(), configs.end(), [](const BenchConfig& k) { return k.quantized; })) {
    PackWriteOptions po;
    po.quantize = true;
    auto bytes = serializePack(scene, po);
    if (!bytes) return bytes.error();
    auto q = parsePack(bytes->data(), bytes->size(), "quantised scene");
    if (!q) return q.error();
    variants.quantizedScene = std::make_unique<Scene>(std::move(*q));
  }
  for (const BenchConfig& k : configs) {
    if ((!k.wideIds && !k.quantized) || variants.renderers.count({k.wideIds, k.quantized})) continue;
    RendererConfig vc = rc;
    vc.forceWideIds = k.wideIds;
    auto vr = Renderer::create(device, k.quantized ? *variants.quantizedScene : scene, vc);
    if (!vr) return vr.error();
    variants.renderers[{k.wideIds, k.quantized}] = std::move(*vr);
  }
  return {};
}

// The forward path as the reference (else visbuf with no culling and no LOD).
bool forwardReference(const BenchCommand& c, uint64_t triangles) {
  return c.reference == "forward" || (c.reference == "auto" && triangles <= c.referenceMaxTriangles);
}

// The scene's size and which reference its rows are compared with (and why).
BenchSceneInfo sceneInfo(const BenchCommand& c, uint32_t objects, const Scene& scene) {
  BenchSceneInfo info;
  info.objects = objects;
  info.sceneObjects = uint32_t(scene.objects.size());
  info.triangles = scene.totalTriangles();
  const bool forwardRef = forwardReference(c, info.triangles);
  info.reference = forwardRef ? "forward-full" : "visbuf-full";
  info.referenceReason = c.reference != "auto" ? "asked for (--reference)"
                         : forwardRef
                             ? fmt::format("{} triangles <= --reference-max-triangles {}", info.triangles,
                                           c.referenceMaxTriangles)
                             : fmt::format("{} triangles > --reference-max-triangles {}: forward would be too slow",
                                           info.triangles, c.referenceMaxTriangles);
  return info;
}

struct References {
  std::map<uint32_t, std::vector<std::vector<float>>> colors;  // per sample count, per measured camera
  std::vector<std::vector<uint32_t>> fullIds;  // per measured camera: visbuf with no culling and no LOD
  std::vector<double> frameMs;                 // the single-sampled references' GPU + record times
};

// References, once per measured camera (and per MSAA sample count: each row is compared at its own count).
Result<References> renderReferences(const BenchCommand& c, Renderer& r, const std::vector<Camera>& path,
                                    bool forwardRef, bool needFullIds) {
  References ref;
  ref.fullIds.resize(c.frames);
  r.clearHistory();
  for (uint32_t m : c.msaa) {
    if (m == 1) continue;
    ref.colors[m].resize(c.frames);
    for (uint32_t f = 0; f < c.frames; ++f) {
      FrameOptions ro;
      ro.path = forwardRef ? RenderPath::Forward : RenderPath::Visbuf;
      ro.cull = CullMode::None;
      ro.lodErrorPixels = 0.0f;
      ro.tiledLights = false;
      ro.swRaster = SwRasterMode::Off;  // the exact reference: hardware raster only
      ro.msaa = m;
      auto frame = r.renderFrame(path[c.warmup + f], ro);
      if (!frame) return frame.error();
      ref.colors[m][f] = std::move(frame->color);
    }
  }
  std::vector<std::vector<float>>& refColor = ref.colors[1];
  refColor.resize(c.frames);
  for (uint32_t f = 0; f < c.frames; ++f) {
    const Camera& cam = path[c.warmup + f];
    FrameOptions ro;
    ro.path = forwardRef ? RenderPath::Forward : RenderPath::Visbuf;
    ro.cull = CullMode::None;
    ro.lodErrorPixels = 0.0f;
    ro.tiledLights = false;  // every point light at every pixel
    ro.swRaster = SwRasterMode::Off;  // hardware raster only
    ro.readColor = true;
    ro.readIds = !forwardRef && needFullIds;
    auto frame = r.renderFrame(cam, ro);
    if (!frame) return frame.error();
    refColor[f] = std::move(frame->color);
    if (ro.readIds) ref.fullIds[f] = std::move(frame->ids);
    ref.frameMs.push_back(frame->stats.gpuMs + frame->stats.cpuRecordMs);
    if (forwardRef && needFullIds) {
      FrameOptions io = ro;
      io.path = RenderPath::Visbuf;
      io.readColor = false;
      io.readIds = true;
      auto idFrame = r.renderFrame(cam, io);
      if (!idFrame) return idFrame.error();
      ref.fullIds[f] = std::move(idFrame->ids);
    }
  }
  return ref;
}

uint64_t countIdMismatches(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size()) / 2;
  uint64_t n = 0;
  for (size_t i = 0; i + 1 < a.size(); i += 2) n += (a[i] != b[i] || a[i + 1] != b[i + 1]) ? 1 : 0;
  return n;
}

// The row's times and counters: medians (and p95s) over the measured frames.
void summarizeFrames(BenchRow& row, const std::vector<FrameStats>& measured) {
  std::vector<double> frameMs, gpu, cpu, wall, tris, drawn;
  std::vector<std::string> passNames;
  std::vector<double> perCovered;
  for (const FrameStats& s : measured) {
    frameMs.push_back(s.gpuMs + s.cpuRecordMs);
    gpu.push_back(s.gpuMs);
    cpu.push_back(s.cpuRecordMs);
    wall.push_back(s.wallMs);
    tris.push_back(double(s.trianglesDrawn));
    if (s.coveredPixels > 0) perCovered.push_back(double(s.trianglesDrawn) / double(s.coveredPixels));
    drawn.push_back(double(s.cull.drawsRendered));
    for (const auto& [name, ms] : s.graph.passMs)
      if (std::find(passNames.begin(), passNames.end(), name) == passNames.end()) passNames.push_back(name);
  }
  for (const std::string& name : passNames) {  // a pass a frame did not run (a skipped pyramid) took 0 ms
    std::vector<double> v;
    for (const FrameStats& s : measured) {
      double ms = 0.0;
      for (const auto& [n, t] : s.graph.passMs)
        if (n == name) ms += t;
      v.push_back(ms);
    }
    row.passMs.push_back({name, {median(v), p95(v)}});
  }
  row.frameMedian = median(frameMs);
  row.frameP95 = p95(frameMs);
  row.gpuMedian = median(gpu);
  row.gpuP95 = p95(gpu);
  row.cpuMedian = median(cpu);
  row.wallMedian = median(wall);
  row.trianglesMedian = median(tris);
  row.drawnMedian = median(drawn);
  row.trianglesPerCoveredPixel = perCovered.empty() ? 0.0 : median(perCovered);
  {
    std::vector<double> present, pairs;
    for (const FrameStats& s : measured)
      present.push_back(s.shade.materialsPresent), pairs.push_back(s.shade.classifiedTiles);
    row.materialsPresent = median(present);
    row.classifiedTiles = median(pairs);
  }
  row.sceneBytes = measured.back().sceneBytes;
  row.targetBytesPerPixel = measured.back().targetBytesPerPixel;
  std::vector<double> perSample;
  for (const FrameStats& s : measured) perSample.push_back(double(s.shade.perSamplePixels));
  row.perSamplePixels = median(perSample);
}

// PSNR over all measured frames = that of their mean squared error; worst = lowest frame.
void summarizeErrors(BenchRow& row, const std::vector<ImageError>& errors) {
  double mseSum = 0.0;
  row.psnrWorst = INFINITY;
  for (const ImageError& e : errors) {
    mseSum += std::isfinite(e.psnr) ? std::pow(10.0, -e.psnr / 10.0) : 0.0;
    row.psnrWorst = std::min(row.psnrWorst, e.psnr);
    row.maxAbs = std::max(row.maxAbs, e.maxAbs);
    row.meanAbs += e.meanAbs / double(errors.size());
    row.differingFraction += e.differingFraction / double(errors.size());
  }
  const double mse = mseSum / double(errors.size());
  row.psnrMean = mse > 0 ? 10.0 * std::log10(1.0 / mse) : INFINITY;
}

// One configuration along the whole path (history cleared first), its measured frames compared with the
// references.
Result<BenchRow> measureConfig(const BenchCommand& c, Renderer& rk, const BenchConfig& k,
                               const std::vector<Camera>& path, const References& ref, const BenchSceneInfo& info,
                               uint32_t pixels) {
  rk.clearHistory();
  const bool idComparable = k.path == RenderPath::Visbuf && k.lod <= 0.0f && k.msaa == 1;  // (1 ID per pixel)
  std::vector<FrameStats> measured;
  std::vector<ImageError> errors;
  uint64_t mismatches = 0;
  for (size_t i = 0; i < path.size(); ++i) {
    const bool measure = i >= c.warmup;
    FrameOptions fo;
    fo.path = k.path;
    fo.cull = k.cull;
    fo.lodErrorPixels = k.lod;
    fo.msaa = k.msaa;
    fo.readColor = measure;
    fo.readIds = measure && idComparable;
    fo.shading = k.shading;
    fo.swRaster = k.swRaster;
    auto frame = rk.renderFrame(path[i], fo);
    if (!frame) return frame.error();
    if (!measure) continue;
    const size_t f = i - c.warmup;
    measured.push_back(frame->stats);
    errors.push_back(compareColor(frame->color, ref.colors.at(k.msaa)[f]));
    if (idComparable) mismatches += countIdMismatches(frame->ids, ref.fullIds[f]);
  }
  BenchRow row;
  if (k.msaa == 1) {  // bandwidth: the raster's real writes at the last measured camera (not timed: the counting
                      // costs atomics; single-sampled only)
    FrameOptions bo;
    bo.path = k.path;
    bo.cull = k.cull;
    bo.lodErrorPixels = k.lod;
    bo.readColor = false;
    bo.countOverdraw = true;
    bo.shading = k.shading;
    auto frame = rk.renderFrame(path.back(), bo);
    if (!frame) return frame.error();
    row.rasterWritesPerPixel = frame->stats.rasterWritesPerPixel;
    row.bytesWrittenPerPixel = frame->stats.bytesWrittenPerPixel;
  }
  row.objects = info.objects;
  row.config = k;
  row.reference = info.reference;
  row.idBits = k.path != RenderPath::Visbuf ? "-" : rk.idEncoding().wide ? "64" : "32";
  if (k.path == RenderPath::Visbuf) {
    row.shading = shadingModeName(measured.back().shade.mode);
    row.raster = measured.back().sw.on ? "hw+sw" : "hw";
  }
  summarizeFrames(row, measured);
  summarizeErrors(row, errors);
  if (idComparable) {
    row.idMismatches = mismatches;
    row.idPixels = uint64_t(pixels) * measured.size();
  }
  return row;
}

// The scene of one object count: its references, then every configuration, a console line each; appends the
// scene and its rows to `results`.
Status benchScene(const BenchCommand& c, gpu::Device& device, uint32_t width, uint32_t height,
                  const std::vector<BenchConfig>& configs, uint32_t objects, BenchResults& results) {
  auto scene = loadScene(sceneOptions(c, objects));
  if (!scene) return scene.error();
  RendererConfig rc;
  rc.width = width;
  rc.height = height;
  auto renderer = Renderer::create(device, *scene, rc);
  if (!renderer) return renderer.error();
  Renderer& r = **renderer;
  PrecisionVariants variants;
  if (Status s = createVariants(device, *scene, rc, configs, variants); !s) return s;
  const std::vector<Camera> path = benchCameraPath(*scene, c.warmup, c.frames);

  BenchSceneInfo info = sceneInfo(c, objects, *scene);
  const bool forwardRef = forwardReference(c, info.triangles);
  const bool needFullIds = std::any_of(configs.begin(), configs.end(), [](const BenchConfig& k) {
    return k.path == RenderPath::Visbuf && k.lod <= 0.0f;
  });
  std::printf("scene %s, %u objects, %llu full-detail triangles; reference: %s (%s)\n", printable(scene->name).c_str(),
              info.sceneObjects, (unsigned long long)info.triangles, info.reference.c_str(),
              info.referenceReason.c_str());

  auto ref = renderReferences(c, r, path, forwardRef, needFullIds);
  if (!ref) return ref.error();
  info.referenceFrameMsMedian = median(ref->frameMs);

  for (const BenchConfig& k : configs) {
    Renderer& rk = k.wideIds || k.quantized ? *variants.renderers.at({k.wideIds, k.quantized}) : r;
    auto row = measureConfig(c, rk, k, path, *ref, info, width * height);
    if (!row) return row.error();
    std::printf("  %-10s %-5s %-10s %-9s lod %-4s ids %-2s %-5s  frame %9.3f ms (p95 %9.3f)  tris %12.0f  PSNR %7s / %7s dB  ids %s\n",
                pathLabel(k).c_str(), row->raster.c_str(), row->shading.c_str(), cullModeName(k.cull), k.lodLabel.c_str(),
                row->idBits.c_str(), k.quantized ? "q16" : "float", row->frameMedian, row->frameP95,
                row->trianglesMedian, dbText(row->psnrMean).c_str(), dbText(row->psnrWorst).c_str(),
                row->idMismatches ? fmt::format("{}", *row->idMismatches).c_str() : "n/a");
    std::fflush(stdout);
    results.rows.push_back(std::move(*row));
  }
  results.scenes.push_back(info);
  return {};
}

}  // namespace

int runBench(const BenchCommand& c) {
  auto size = parseSize(c.size);
  if (!size) return benchFail(size.error());
  auto devOptions = gpu::parseDeviceOption(c.device, {.validation = c.validation});
  if (!devOptions) return benchFail(devOptions.error());
  if (c.paths.empty() || c.cull.empty() || c.lod.empty() || c.shading.empty())
    return benchFail({ErrorCode::InvalidArgument, "--paths, --cull, --lod and --shading need at least one value each"});

  BenchResults results;
  auto configs = configMatrix(c, results.skipped);
  if (!configs) return benchFail(configs.error());

  std::vector<uint32_t> objectCounts = c.objects;
  if (objectCounts.empty()) {
    if (c.scene == "field" || c.scene == "city")
      objectCounts = {100, 1000};
    else
      objectCounts = {0};
  }

  // The output folder and the memory for the largest scene before any work (bad input, exit 1).
  if (Status s = checkOutputFolder("-o", c.output); !s) return benchFail(s.error());
  // The files the folder gets are never inputs of this run (writeBenchReport, bench_in_flight.cpp); checked again
  // by commitFile when they are written, once every scene has been read.
  const std::filesystem::path outFolder(c.output);
  std::vector<OutputFile> outputs;
  for (const char* name : {"bench.json", "bench.csv", "bench.md", "bench.svg"})
    outputs.push_back({"-o", (outFolder / name).string(), true});
  noteSceneInputs(sceneOptions(c, 0));
  if (Status s = checkOutputs(outputs); !s) return benchFail(s.error());
  RenderBudgetInput budget;
  budget.objects = *std::max_element(objectCounts.begin(), objectCounts.end());
  budget.lights = c.lights;
  budget.materials = c.materials;
  budget.width = size->first;
  budget.height = size->second;
  budget.msaa = *std::max_element(c.msaa.begin(), c.msaa.end());
  budget.gbuffer = std::find(c.paths.begin(), c.paths.end(), "gbuffer") != c.paths.end();
  budget.ids = true;
  budget.reference = true;
  const std::string asked = fmt::format("--objects {} at {}x{}", budget.objects, size->first, size->second);
  if (Status s = checkMemory(estimateRender(budget), nullptr, asked); !s) return benchFail(s.error());
  std::error_code ec;
  std::filesystem::create_directories(c.output, ec);
  if (ec) return benchFail({ErrorCode::IoError, fmt::format("{}: cannot create the output folder", c.output)});

  auto device = gpu::Device::create(*devOptions);
  if (!device) return benchFail(device.error());
  if (Status s = checkMemory(estimateRender(budget), device->get(), asked); !s) return benchFail(s.error());
  const std::string deviceName = (*device)->name();
  if (!c.inFlight.empty()) {
    std::vector<Scene> inFlightScenes;
    for (uint32_t objects : objectCounts) {
      auto scene = loadScene(sceneOptions(c, objects));
      if (!scene) return benchFail(scene.error());
      inFlightScenes.push_back(std::move(*scene));
    }
    std::printf("visbuf bench --in-flight: %zu scene sizes, %u+%u frames, %u pairs, device %s\n", objectCounts.size(),
                c.warmup, c.frames, c.pairs, deviceName.c_str());
    const int rc = runInFlightBench(c, **device, inFlightScenes, size->first, size->second, c.output);
    if (rc == 0 && (*device)->validationEnabled() && (*device)->validationMessages() > 0) {
      std::fprintf(stderr, "visbuf bench: %u validation message(s)\n", (*device)->validationMessages());
      return 3;
    }
    return rc;
  }
  std::printf("visbuf bench: %s, %zu configurations x %zu scene sizes, %u+%u frames each, device %s\n",
              printable(c.scene).c_str(), configs->size(), objectCounts.size(), c.warmup, c.frames, deviceName.c_str());
  for (const auto& s : results.skipped)
    std::printf("  skipped %s/%s: %s\n", s["path"].get<std::string>().c_str(), s["cull"].get<std::string>().c_str(),
                s["reason"].get<std::string>().c_str());

  for (uint32_t objects : objectCounts)
    if (Status s = benchScene(c, **device, size->first, size->second, *configs, objects, results); !s)
      return benchFail(s.error());

  markParetoFront(results.rows);
  if (Status s = writeBenchReport(c, results, deviceName, size->first, size->second); !s) return benchFail(s.error());
  std::printf("wrote %s/bench.{json,csv,md,svg}: %zu rows\n", printable(c.output).c_str(), results.rows.size());

  if ((*device)->validationEnabled() && (*device)->validationMessages() > 0) {
    std::fprintf(stderr, "visbuf bench: %u validation message(s)\n", (*device)->validationMessages());
    return 3;
  }
  return 0;
}

}  // namespace visbuf::tools
