// visbuf bench: run time against error. One scene per object count, a deterministic camera path, and the
// matrix path x cull x LOD rendered in one process on one device (one Renderer per scene size, the
// occlusion history cleared between configurations). Every configuration's measured frames are compared
// with a reference rendered once per camera of the path (forward path, no culling, no LOD; visbuf with no
// culling and no LOD when that would draw too many triangles). Writes bench.json, bench.csv, bench.md and
// bench.svg (time-vs-PSNR plot with the Pareto front) to the output folder, each atomically.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <unistd.h>

#include "bench_in_flight.h"
#include "bench_plot.h"
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
#include "stats_output.h"

namespace visbuf::tools {

namespace {


}  // namespace

void addBenchCommand(CLI::App& app, BenchCommand& c, int argc, char** argv) {
  for (int i = 0; i < argc; ++i) c.commandLine += (i ? " " : "") + shellQuote(argv[i]);
  CLI::App* sub = app.add_subcommand(
      "bench", "time against error: a camera path through a matrix of path x culling x LOD, per scene size");
  sub->add_option("--scene", c.scene, "field | city | a .gltf/.glb file | a baked pack (.vbp)")->capture_default_str();
  sub->add_option("--objects", c.objects,
                  "object counts, one scene each (default: 100,1000 for field and city; a file's own objects)")
      ->delimiter(',')
      ->check(unsignedIn(1, UINT32_MAX));
  sub->add_option("--seed", c.seed, "scene generator seed")->check(unsignedIn(0, UINT64_MAX))->capture_default_str();
  sub->add_option("--mesh", c.mesh, "field: .gltf/.glb mesh to instance (default: procedural torus knot)");
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

int benchFail(const Error& e) {
  std::fprintf(stderr, "visbuf bench: error (%s): %s\n", errorCodeName(e.code),
               printable(e.message, e.code == ErrorCode::NoDevice).c_str());
  return 1;
}

// ---- camera path ---------------------------------------------------------------------------------------

// Cameras for frames -warmup .. frames-1 (index 0 of the result is the first warm-up frame). The path is a
// function of t = frame / frames only, so it is reproducible and the warm-up frames lead into it.
// city: a walk down the default camera's avenue, looking left and right. Anything else: a 90-degree arc
// around the centre of the scene's bounds, starting at the default camera and spiralling in to 55% of its
// horizontal distance, rising by up to 20% of it mid-path, always looking at the centre.
std::vector<Camera> benchCameraPath(const Scene& scene, uint32_t warmup, uint32_t frames) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const Object& o : scene.objects) {
    glm::dvec4 s = objectBoundsWorld(scene, o);
    lo = glm::min(lo, glm::dvec3(s) - s.w);
    hi = glm::max(hi, glm::dvec3(s) + s.w);
  }
  if (scene.objects.empty()) lo = hi = glm::dvec3(0.0);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double boundsRadius = std::max(0.5 * glm::length(hi - lo), 1e-3);
  const Camera& base = scene.defaultCamera;
  std::vector<Camera> path;
  for (int i = -int(warmup); i < int(frames); ++i) {
    const double t = double(i) / double(frames);
    Camera c = base;
    if (scene.name == "city") {
      glm::dvec3 dir = base.target - base.position;
      dir.y = 0.0;
      dir = glm::length(dir) > 0 ? glm::normalize(dir) : glm::dvec3(0, 0, -1);
      const double walk = std::min(150.0, 0.3 * boundsRadius);
      c.position = base.position + dir * (walk * t) + glm::dvec3(0.0, 0.5 * std::sin(6.283185307 * t), 0.0);
      const double yaw = 0.6 * std::sin(6.283185307 * t);
      const glm::dvec3 look(dir.x * std::cos(yaw) - dir.z * std::sin(yaw), 0.05,
                            dir.x * std::sin(yaw) + dir.z * std::cos(yaw));
      c.target = c.position + look;
    } else {
      glm::dvec3 rel = base.position - centre;
      double r0 = glm::length(glm::dvec2(rel.x, rel.z));
      if (r0 < 1e-6 * boundsRadius) r0 = 2.0 * boundsRadius, rel = glm::dvec3(0, 0, r0);
      const double az0 = std::atan2(rel.x, rel.z);
      const double az = az0 + 1.5707963268 * t;
      const double r = r0 * (1.0 - 0.45 * t);
      const double y = rel.y + 0.2 * r0 * std::sin(3.14159265359 * t);
      c.position = centre + glm::dvec3(r * std::sin(az), y, r * std::cos(az));
      c.target = centre;
    }
    path.push_back(c);
  }
  return path;
}

// ---- statistics -----------------------------------------------------------------------------------------

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

namespace {

double p95(std::vector<double> v) {  // nearest rank
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t rank = size_t(std::ceil(0.95 * double(v.size())));
  return v[std::clamp<size_t>(rank, 1, v.size()) - 1];
}

nlohmann::json dbJson(double db) { return std::isfinite(db) ? nlohmann::json(db) : nlohmann::json("inf"); }
std::string dbText(double db) { return std::isfinite(db) ? fmt::format("{:.2f}", db) : std::string("inf"); }

struct Config {
  RenderPath path;
  CullMode cull;
  float lod;          // <= 0: off
  std::string lodLabel;
  bool wideIds = false;  // visbuf: the 64-bit ID target forced where the renderer would pick 32 bits
  bool quantized = false;  // vertices quantised as `bake --quantize` stores them (pack round trip in memory)
  uint32_t msaa = 1;       // samples per pixel (FrameOptions::msaa); its reference renders at the same count
  ShadingMode shading = ShadingMode::Auto;  // visbuf only
  SwRasterMode swRaster = SwRasterMode::Auto;  // visbuf only
};

// "visbuf", or "visbuf 4x" with MSAA (tables).
std::string pathLabel(const Config& k) {
  return k.msaa > 1 ? fmt::format("{} {}x", renderPathName(k.path), k.msaa) : std::string(renderPathName(k.path));
}


struct Row {
  uint32_t objects = 0;
  Config config;
  std::vector<std::pair<std::string, std::pair<double, double>>> passMs;  // name -> median, p95
  double frameMedian = 0, frameP95 = 0, gpuMedian = 0, gpuP95 = 0, cpuMedian = 0, wallMedian = 0;
  double trianglesMedian = 0, drawnMedian = 0;
  // Visbuf, single-sampled: triangles drawn per covered pixel (median; a visibility buffer's ideal is about 1);
  // 0 where the path does not count covered pixels.
  double trianglesPerCoveredPixel = 0;
  uint64_t sceneBytes = 0, targetBytesPerPixel = 0;
  // One extra (untimed) frame at the last measured camera with countOverdraw: depth-passing raster writes per
  // pixel and the bytes written per pixel (FrameStats::bytesWrittenPerPixel).
  double rasterWritesPerPixel = 0, bytesWrittenPerPixel = 0;
  double perSamplePixels = 0;  // visbuf MSAA: median pixels shaded per distinct sample ID
  double psnrMean = INFINITY, psnrWorst = INFINITY, maxAbs = 0, meanAbs = 0, differingFraction = 0;
  std::optional<uint64_t> idMismatches;  // pixels over all measured frames; empty: not comparable
  uint64_t idPixels = 0;
  std::string reference;
  std::string idBits;  // "32" / "64": bits per pixel of the visbuf ID target; "-": forward (none)
  std::string shading = "-";  // visbuf: the shading mode used (uber / classified); "-": other paths
  std::string raster = "hw";  // visbuf: "hw+sw" where the last measured frame used the software micro-raster
  double materialsPresent = 0, classifiedTiles = 0;  // classified: medians over the measured frames
  bool pareto = false;
};

struct SceneInfo {
  uint32_t objects = 0;  // as asked (0: the file's own)
  uint32_t sceneObjects = 0;
  uint64_t triangles = 0;
  std::string reference;
  std::string referenceReason;
  double referenceFrameMsMedian = 0;
};

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

std::string utcNow() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

namespace {

uint64_t countIdMismatches(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size()) / 2;
  uint64_t n = 0;
  for (size_t i = 0; i + 1 < a.size(); i += 2) n += (a[i] != b[i] || a[i + 1] != b[i + 1]) ? 1 : 0;
  return n;
}

}  // namespace

int runBench(const BenchCommand& c) {
  auto size = parseSize(c.size);
  if (!size) return benchFail(size.error());
  auto devOptions = gpu::parseDeviceOption(c.device, {.validation = c.validation});
  if (!devOptions) return benchFail(devOptions.error());
  if (c.paths.empty() || c.cull.empty() || c.lod.empty() || c.shading.empty())
    return benchFail({ErrorCode::InvalidArgument, "--paths, --cull, --lod and --shading need at least one value each"});

  // The configuration matrix.
  std::vector<float> lods;
  for (const std::string& s : c.lod) {
    if (s == "off") {
      lods.push_back(0.0f);
      continue;
    }
    char* end = nullptr;
    const float v = std::strtof(s.c_str(), &end);
    if (s.empty() || *end != '\0' || !std::isfinite(v) || v < 0.0f)
      return benchFail({ErrorCode::InvalidArgument, fmt::format("--lod '{}': expected off or a threshold >= 0 px", s)});
    lods.push_back(v);
  }
  std::vector<Config> configs;
  nlohmann::json skipped = nlohmann::json::array();
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
  if (configs.empty()) return benchFail({ErrorCode::InvalidArgument, "no configuration left to run"});

  std::vector<uint32_t> objectCounts = c.objects;
  if (objectCounts.empty()) {
    if (c.scene == "field" || c.scene == "city")
      objectCounts = {100, 1000};
    else
      objectCounts = {0};
  }

  // The output folder and the memory for the largest scene before any work (bad input, exit 1).
  if (Status s = checkOutputFolder("-o", c.output); !s) return benchFail(s.error());
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
              printable(c.scene).c_str(), configs.size(), objectCounts.size(), c.warmup, c.frames, deviceName.c_str());
  for (const auto& s : skipped)
    std::printf("  skipped %s/%s: %s\n", s["path"].get<std::string>().c_str(), s["cull"].get<std::string>().c_str(),
                s["reason"].get<std::string>().c_str());

  std::vector<Row> rows;
  std::vector<SceneInfo> scenes;
  const uint32_t pixels = size->first * size->second;
  for (uint32_t objects : objectCounts) {
    auto scene = loadScene(sceneOptions(c, objects));
    if (!scene) return benchFail(scene.error());
    RendererConfig rc;
    rc.width = size->first;
    rc.height = size->second;
    auto renderer = Renderer::create(**device, *scene, rc);
    if (!renderer) return benchFail(renderer.error());
    Renderer& r = **renderer;
    // The other precision variants of the same scene: 64-bit IDs forced (--ids wide), quantised vertices
    // (--vertices quantized: the scene through an in-memory pack written with quantisation and read back).
    std::unique_ptr<Scene> quantizedScene;
    if (std::any_of(configs.begin(), configs.end(), [](const Config& k) { return k.quantized; })) {
      PackWriteOptions po;
      po.quantize = true;
      auto bytes = serializePack(*scene, po);
      if (!bytes) return benchFail(bytes.error());
      auto q = parsePack(bytes->data(), bytes->size(), "quantised scene");
      if (!q) return benchFail(q.error());
      quantizedScene = std::make_unique<Scene>(std::move(*q));
    }
    std::map<std::pair<bool, bool>, std::unique_ptr<Renderer>> variants;  // (wide IDs, quantised) -> renderer
    for (const Config& k : configs) {
      if ((!k.wideIds && !k.quantized) || variants.count({k.wideIds, k.quantized})) continue;
      RendererConfig vc = rc;
      vc.forceWideIds = k.wideIds;
      auto vr = Renderer::create(**device, k.quantized ? *quantizedScene : *scene, vc);
      if (!vr) return benchFail(vr.error());
      variants[{k.wideIds, k.quantized}] = std::move(*vr);
    }
    const std::vector<Camera> path = benchCameraPath(*scene, c.warmup, c.frames);

    SceneInfo info;
    info.objects = objects;
    info.sceneObjects = uint32_t(scene->objects.size());
    info.triangles = scene->totalTriangles();
    const bool forwardRef = c.reference == "forward" ||
                            (c.reference == "auto" && info.triangles <= c.referenceMaxTriangles);
    info.reference = forwardRef ? "forward-full" : "visbuf-full";
    info.referenceReason = c.reference != "auto" ? "asked for (--reference)"
                           : forwardRef
                               ? fmt::format("{} triangles <= --reference-max-triangles {}", info.triangles,
                                             c.referenceMaxTriangles)
                               : fmt::format("{} triangles > --reference-max-triangles {}: forward would be too slow",
                                             info.triangles, c.referenceMaxTriangles);
    const bool needFullIds = std::any_of(configs.begin(), configs.end(), [](const Config& k) {
      return k.path == RenderPath::Visbuf && k.lod <= 0.0f;
    });
    std::printf("scene %s, %u objects, %llu full-detail triangles; reference: %s (%s)\n", printable(scene->name).c_str(),
                info.sceneObjects, (unsigned long long)info.triangles, info.reference.c_str(),
                info.referenceReason.c_str());

    // References, once per measured camera (and per MSAA sample count: each row is compared at its own count).
    std::map<uint32_t, std::vector<std::vector<float>>> refColors;
    std::vector<std::vector<uint32_t>> fullIds(c.frames);
    std::vector<double> refMs;
    r.clearHistory();
    for (uint32_t m : c.msaa) {
      if (m == 1) continue;
      refColors[m].resize(c.frames);
      for (uint32_t f = 0; f < c.frames; ++f) {
        FrameOptions ro;
        ro.path = forwardRef ? RenderPath::Forward : RenderPath::Visbuf;
        ro.cull = CullMode::None;
        ro.lodErrorPixels = 0.0f;
        ro.tiledLights = false;
        ro.swRaster = SwRasterMode::Off;  // the exact reference: hardware raster only
        ro.msaa = m;
        auto frame = r.renderFrame(path[c.warmup + f], ro);
        if (!frame) return benchFail(frame.error());
        refColors[m][f] = std::move(frame->color);
      }
    }
    std::vector<std::vector<float>>& refColor = refColors[1];
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
      if (!frame) return benchFail(frame.error());
      refColor[f] = std::move(frame->color);
      if (ro.readIds) fullIds[f] = std::move(frame->ids);
      refMs.push_back(frame->stats.gpuMs + frame->stats.cpuRecordMs);
      if (forwardRef && needFullIds) {
        FrameOptions io = ro;
        io.path = RenderPath::Visbuf;
        io.readColor = false;
        io.readIds = true;
        auto idFrame = r.renderFrame(cam, io);
        if (!idFrame) return benchFail(idFrame.error());
        fullIds[f] = std::move(idFrame->ids);
      }
    }
    info.referenceFrameMsMedian = median(refMs);

    for (const Config& k : configs) {
      Renderer& rk = k.wideIds || k.quantized ? *variants.at({k.wideIds, k.quantized}) : r;
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
        if (!frame) return benchFail(frame.error());
        if (!measure) continue;
        const size_t f = i - c.warmup;
        measured.push_back(frame->stats);
        errors.push_back(compareColor(frame->color, refColors.at(k.msaa)[f]));
        if (idComparable) mismatches += countIdMismatches(frame->ids, fullIds[f]);
      }
      Row row;
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
        if (!frame) return benchFail(frame.error());
        row.rasterWritesPerPixel = frame->stats.rasterWritesPerPixel;
        row.bytesWrittenPerPixel = frame->stats.bytesWrittenPerPixel;
      }
      row.objects = objects;
      row.config = k;
      row.reference = info.reference;
      row.idBits = k.path != RenderPath::Visbuf ? "-" : rk.idEncoding().wide ? "64" : "32";
      if (k.path == RenderPath::Visbuf) {
        row.shading = shadingModeName(measured.back().shade.mode);
        row.raster = measured.back().sw.on ? "hw+sw" : "hw";
      }
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
      // PSNR over all measured frames = that of their mean squared error; worst = lowest frame.
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
      if (idComparable) {
        row.idMismatches = mismatches;
        row.idPixels = uint64_t(pixels) * measured.size();
      }
      std::printf("  %-10s %-5s %-10s %-9s lod %-4s ids %-2s %-5s  frame %9.3f ms (p95 %9.3f)  tris %12.0f  PSNR %7s / %7s dB  ids %s\n",
                  pathLabel(k).c_str(), row.raster.c_str(), row.shading.c_str(), cullModeName(k.cull), k.lodLabel.c_str(),
                  row.idBits.c_str(), k.quantized ? "q16" : "float", row.frameMedian, row.frameP95,
                  row.trianglesMedian, dbText(row.psnrMean).c_str(), dbText(row.psnrWorst).c_str(),
                  row.idMismatches ? fmt::format("{}", *row.idMismatches).c_str() : "n/a");
      std::fflush(stdout);
      rows.push_back(std::move(row));
    }
    scenes.push_back(info);
  }

  // Pareto front per scene size: lower frame time, higher PSNR (mean; within 0.1 dB counts as equal).
  for (uint32_t objects : objectCounts) {
    std::vector<size_t> idx;
    std::vector<double> t, q;
    for (size_t i = 0; i < rows.size(); ++i)
      if (rows[i].objects == objects) {
        idx.push_back(i);
        t.push_back(rows[i].frameMedian);
        q.push_back(std::isfinite(rows[i].psnrMean) ? rows[i].psnrMean : 1e300);
      }
    std::vector<bool> front = paretoFront(t, q);
    for (size_t j = 0; j < idx.size(); ++j) rows[idx[j]].pareto = front[j];
  }

  // Every pass name, in first-seen order (CSV columns).
  std::vector<std::string> passNames;
  for (const Row& row : rows)
    for (const auto& p : row.passMs)
      if (std::find(passNames.begin(), passNames.end(), p.first) == passNames.end()) passNames.push_back(p.first);
  auto passOf = [](const Row& row, const std::string& name) -> const std::pair<double, double>* {
    for (const auto& p : row.passMs)
      if (p.first == name) return &p.second;
    return nullptr;
  };
  auto objectsLabel = [](uint32_t n) { return n ? fmt::format("{}", n) : std::string("file"); };

  const std::string date = utcNow();
  // bench.json
  nlohmann::json j;
  stampInvocation(j, deviceName);
  j["date"] = date;
  j["scene"] = c.scene;
  j["mesh"] = c.mesh;
  j["materials"] = c.materials;
  j["seed"] = c.seed;
  j["width"] = size->first;
  j["height"] = size->second;
  j["frames"] = c.frames;
  j["warmup"] = c.warmup;
  j["cameraPath"] = c.scene == "city"
                        ? "walk from the default camera along its avenue (min(150, 0.3 x bounds radius)), yaw +-0.6 rad"
                        : "90-degree arc around the bounds centre from the default camera, radius 100% -> 55%, "
                          "height +20% at mid-path";
  j["frameMs"] = "GPU time of all passes + CPU time to cull (forward) and record; medians over measured frames";
  j["psnrMean"] = "PSNR of the mean squared error over the measured frames (\"inf\": identical)";
  j["skipped"] = skipped;
  nlohmann::json sj = nlohmann::json::array();
  for (const SceneInfo& s : scenes)
    sj.push_back({{"objects", s.objects},
                  {"sceneObjects", s.sceneObjects},
                  {"fullDetailTriangles", s.triangles},
                  {"reference", s.reference},
                  {"referenceReason", s.referenceReason},
                  {"referenceFrameMsMedian", s.referenceFrameMsMedian}});
  j["scenes"] = sj;
  nlohmann::json rj = nlohmann::json::array();
  for (const Row& row : rows) {
    nlohmann::json x;
    x["objects"] = row.objects;
    x["path"] = renderPathName(row.config.path);
    x["cull"] = cullModeName(row.config.cull);
    x["lod"] = row.config.lodLabel;
    x["lodErrorPixels"] = row.config.lod;
    x["idBits"] = row.idBits;
    x["shading"] = row.shading;
    x["raster"] = row.raster;
    if (row.shading == "classified") {
      x["materialsPresent"] = row.materialsPresent;
      x["tileMaterialPairs"] = row.classifiedTiles;
    }
    x["vertices"] = row.config.quantized ? "quantized" : "float";
    x["msaa"] = row.config.msaa;
    x["perSamplePixels"] = row.perSamplePixels;
    nlohmann::json passes = nlohmann::json::object();
    for (const auto& [name, v] : row.passMs) passes[name] = {{"median", v.first}, {"p95", v.second}};
    x["passMs"] = passes;
    x["frameMs"] = {{"median", row.frameMedian}, {"p95", row.frameP95}};
    x["gpuMs"] = {{"median", row.gpuMedian}, {"p95", row.gpuP95}};
    x["cpuRecordMs"] = {{"median", row.cpuMedian}};
    x["wallMs"] = {{"median", row.wallMedian}};
    x["trianglesDrawn"] = row.trianglesMedian;
    x["objectsDrawn"] = row.drawnMedian;
    if (row.trianglesPerCoveredPixel > 0) x["trianglesPerCoveredPixel"] = row.trianglesPerCoveredPixel;
    x["sceneBytes"] = row.sceneBytes;
    x["targetBytesPerPixel"] = row.targetBytesPerPixel;
    x["rasterWritesPerPixel"] = row.rasterWritesPerPixel;
    x["bytesWrittenPerPixel"] = row.bytesWrittenPerPixel;
    x["error"] = {{"psnrMean", dbJson(row.psnrMean)},
                  {"psnrWorst", dbJson(row.psnrWorst)},
                  {"maxAbs", row.maxAbs},
                  {"meanAbs", row.meanAbs},
                  {"differingFraction", row.differingFraction}};
    if (row.idMismatches) {
      x["idMismatches"] = *row.idMismatches;
      x["idPixelsCompared"] = row.idPixels;
    } else {
      x["idMismatches"] = "n/a";
    }
    x["reference"] = row.reference;
    x["pareto"] = row.pareto;
    rj.push_back(x);
  }
  j["rows"] = rj;

  // bench.csv
  std::string csv =
      "scene,objects,path,cull,lod_px,id_bits,vertices,frames,frame_ms_median,frame_ms_p95,gpu_ms_median,gpu_ms_p95,"
      "cpu_record_ms_median,wall_ms_median,triangles_median,objects_drawn_median,scene_bytes,"
      "target_bytes_per_pixel,psnr_mean_db,psnr_worst_db,max_abs_error,mean_abs_error,differing_fraction,"
      "id_mismatches,reference,pareto";
  for (std::string n : passNames) {  // "depth pyramid" -> pass_depth_pyramid_ms_median
    std::replace(n.begin(), n.end(), ' ', '_');
    csv += fmt::format(",pass_{0}_ms_median,pass_{0}_ms_p95", n);
  }
  csv += ",raster_writes_per_pixel,bytes_written_per_pixel,msaa,per_sample_pixels,shading,raster,"
         "triangles_per_covered_pixel\n";  // appended: earlier columns fixed
  for (const Row& row : rows) {
    csv += fmt::format("{},{},{},{},{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.0f},{:.0f},{},{},{},{},{:.6f},{:.6f},{:.6f},{},{},{}",
                       c.scene.find(',') == std::string::npos ? c.scene : "\"" + c.scene + "\"", row.objects,
                       renderPathName(row.config.path), cullModeName(row.config.cull), row.config.lodLabel,
                       row.idBits, row.config.quantized ? "quantized" : "float", c.frames,
                       row.frameMedian, row.frameP95, row.gpuMedian, row.gpuP95, row.cpuMedian, row.wallMedian,
                       row.trianglesMedian, row.drawnMedian, row.sceneBytes, row.targetBytesPerPixel,
                       dbText(row.psnrMean), dbText(row.psnrWorst), row.maxAbs, row.meanAbs, row.differingFraction,
                       row.idMismatches ? fmt::format("{}", *row.idMismatches) : std::string("n/a"), row.reference,
                       row.pareto ? 1 : 0);
    for (const std::string& n : passNames) {
      const auto* p = passOf(row, n);
      csv += p ? fmt::format(",{:.4f},{:.4f}", p->first, p->second) : std::string(",,");
    }
    csv += fmt::format(",{:.4f},{:.2f},{},{:.0f},{},{},{}\n", row.rasterWritesPerPixel, row.bytesWrittenPerPixel,
                       row.config.msaa, row.perSamplePixels, row.shading, row.raster,
                       row.trianglesPerCoveredPixel > 0 ? fmt::format("{:.3f}", row.trianglesPerCoveredPixel) : "");
  }

  // bench.md
  std::string md = fmt::format("`{}`\n\n", c.commandLine);
  md += fmt::format("{} ({} measured frames after {} warm-up along the camera path, {}x{}), {}. ", deviceName, c.frames,
                    c.warmup, size->first, size->second, date);
  md += "frame ms = GPU passes + CPU cull/record (median, p95); PSNR vs the reference: over all measured frames / worst "
        "frame; ID mism. = pixels whose decoded (object, triangle) differ from visbuf with no culling and no LOD; "
        "P = on the Pareto front (time vs PSNR; PSNRs within 0.1 dB count as equal); B/px = bytes per pixel of the "
        "path's targets / bytes written per pixel at the last camera (raster writes x bytes per fragment + resolve "
        "colour; clears not counted).\n\n";
  for (const SceneInfo& s : scenes)
    md += fmt::format("- {} objects: {} objects, {} full-detail triangles; reference {} ({:.1f} ms a frame)\n",
                      objectsLabel(s.objects), s.sceneObjects, s.triangles, s.reference, s.referenceFrameMsMedian);
  md += "\n| objects | path | cull | LOD px | IDs | vertices | frame ms | p95 | GPU passes ms (median) | CPU rec ms | triangles | "
        "tri/px | drawn | scene MiB | B/px | PSNR dB | worst dB | max err | px > 1/255 | ID mism. | P |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& row : rows) {
    std::string passes;
    for (const auto& [name, v] : row.passMs) passes += fmt::format("{}{} {:.2f}", passes.empty() ? "" : ", ", name, v.first);
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {:.2f} | {:.2f} | {} | {:.2f} | {:.0f} | {} | {:.0f} | {:.1f} | {} / {:.1f} | {} | {} | "
                      "{:.4f} | {:.3f}% | {} | {} |\n",
                      objectsLabel(row.objects),
                      row.shading == "-" ? pathLabel(row.config)
                                         : fmt::format("{} ({}, {})", pathLabel(row.config), row.shading, row.raster),
                      cullModeName(row.config.cull), row.config.lodLabel, row.idBits, row.config.quantized ? "q16" : "float", row.frameMedian, row.frameP95, passes, row.cpuMedian, row.trianglesMedian,
                      row.trianglesPerCoveredPixel > 0 ? fmt::format("{:.2f}", row.trianglesPerCoveredPixel) : "-",
                      row.drawnMedian, row.sceneBytes / 1048576.0, row.targetBytesPerPixel, row.bytesWrittenPerPixel, dbText(row.psnrMean),
                      dbText(row.psnrWorst), row.maxAbs, 100.0 * row.differingFraction,
                      row.idMismatches ? fmt::format("{}", *row.idMismatches) : std::string("n/a"),
                      row.pareto ? "P" : "");
  }
  if (!skipped.empty()) {
    md += "\nSkipped: ";
    for (size_t i = 0; i < skipped.size(); ++i)
      md += fmt::format("{}{}/{}: {}", i ? "; " : "", skipped[i]["path"].get<std::string>(),
                        skipped[i]["cull"].get<std::string>(), skipped[i]["reason"].get<std::string>());
    md += ".\n";
  }

  // bench.svg
  std::vector<PlotPanel> panels;
  for (const SceneInfo& s : scenes) {
    PlotPanel panel;
    panel.title = fmt::format("{}, {} objects, {}x{}, reference {}", c.scene, objectsLabel(s.objects), size->first,
                              size->second, s.reference);
    for (const Row& row : rows)
      if (row.objects == s.objects)
        panel.points.push_back({renderPathName(row.config.path), cullModeName(row.config.cull), row.config.lodLabel,
                                row.frameMedian, row.psnrMean, row.pareto});
    panels.push_back(std::move(panel));
  }
  const std::string svg = renderBenchSvg(panels, fmt::format("visbuf bench: frame time against error ({})", deviceName),
                                         fmt::format("{}   [{}]", c.commandLine, date));

  const std::filesystem::path out(c.output);
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"bench.csv", csv}, {"bench.md", md}, {"bench.svg", svg}}) {
    Status s = writeTextFile((out / name).string(), text);
    if (!s) return benchFail(s.error());
  }
  Status s = writeJsonFile((out / "bench.json").string(), j);
  if (!s) return benchFail(s.error());
  std::printf("wrote %s/bench.{json,csv,md,svg}: %zu rows\n", printable(c.output).c_str(), rows.size());

  if ((*device)->validationEnabled() && (*device)->validationMessages() > 0) {
    std::fprintf(stderr, "visbuf bench: %u validation message(s)\n", (*device)->validationMessages());
    return 3;
  }
  return 0;
}

}  // namespace visbuf::tools
