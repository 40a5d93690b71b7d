// visbuf bench-bake: bake throughput and pack load time over every glTF file of an assets folder.
//
// Per file (.gltf / .glb, found recursively, sorted), --warmup + --repeats runs of the whole chain, each stage
// timed on its own:
//   import    importGltfScene (parse, decode accessors, node hierarchy, materials, skins, animations)
//   geometry  buildImportedScene (meshoptimizer dedup / cache / overdraw / fetch optimisation + LOD chain with
//             its measured error)
//   textures  bakeTextures (decode, resize to a power of two within --max-texture-size, mips, BC compression)
//   write     writePack (serialise + checksums + temporary file + fsync + rename)
//   load      readPack (read + bounds checks + checksums + validateScene): what `render --scene X.vbp` does
//   upload    uploadScene (geometry pool, mesh / object / material tables and the texture classes' BC blocks,
//             through a bounded staging buffer, to the GPU)
// and with --quantize the same write / load / upload for a pack of 20-byte quantised vertices. Medians over the
// repeats, with the median absolute deviation beside each. Beside the times, what the bake costs: the LOD
// chain's recorded error (the coarsest level's, relative to the mesh's bounding-sphere radius), the measured
// quantisation error, and the textures resized (non-power-of-two or over the cap). For files with textures, once
// (untimed): the pack size and GPU texture bytes with BC textures (the default) and with RGBA8 ones
// (`bake --textures rgba8`), and the error of the BC pack's image against the RGBA8 pack's (the default camera,
// 384x384, visbuf path: PSNR and largest channel difference), so the bytes saved stand beside what they cost.
// Files that fail to import or bake are listed with their error and skipped.
// Writes bench-bake.json and bench-bake.md to the output folder, each atomically. Exit codes: 0 ok, 1 failure
// (output folder, device), 2 usage, 3 validation messages.
#include <algorithm>
#include <chrono>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <time.h>
#include <filesystem>
#include <fstream>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/core/image_compare.h"
#include "bench_common.h"  // median, utcNow
#include "cli_checks.h"
#include "commands.h"
#include "invocation.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/gpu_scene.h"
#include "stats_output.h"

namespace visbuf::tools {

namespace fs = std::filesystem;

void addBenchBakeCommand(CLI::App& app, BenchBakeCommand& c, int argc, char** argv) {
  for (int i = 0; i < argc; ++i) c.commandLine += (i ? " " : "") + std::string(argv[i]);
  CLI::App* sub = app.add_subcommand(
      "bench-bake", "bake throughput and pack load time for every glTF file of an assets folder");
  sub->add_option("--assets", c.assets, "folder searched recursively for .gltf / .glb files")
      ->check(nonEmptyPath())
      ->capture_default_str();
  sub->add_option("--repeats", c.repeats, "measured runs per file (medians)")
      ->check(unsignedIn(1, 1000))
      ->capture_default_str();
  sub->add_option("--warmup", c.warmup, "unmeasured runs before them")
      ->check(unsignedIn(0, 100))
      ->capture_default_str();
  sub->add_option("--max-texture-size", c.maxTextureSize, "texture cap of the bake (power of two, 1..16384)")
      ->check(powerOfTwo(16384))
      ->capture_default_str();
  sub->add_flag("--quantize", c.quantize, "also write, load and upload a pack of quantised vertices");
  sub->add_option("--device", c.device, "device for the upload: auto | cpu | gpu | N")->capture_default_str();
  sub->add_flag("--validation", c.validation, "enable Vulkan validation layers (any message fails the run)");
  sub->add_option("-o,--output", c.output, "output folder (bench-bake.json, bench-bake.md)")->capture_default_str();
}

namespace {

using Clock = std::chrono::steady_clock;

int fail(const Error& e) {
  std::fprintf(stderr, "visbuf bench-bake: error (%s): %s\n", errorCodeName(e.code),
               printable(e.message, e.code == ErrorCode::NoDevice).c_str());
  return 1;
}

// Process CPU time (all threads), ms: on a machine shared with other work the wall time of a stage grows with
// the contention, its CPU time does not (for single-threaded stages it is the uncontended wall time).
double cpuMsNow() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

// Wall and CPU time of one stage, started at construction.
struct StageTimer {
  Clock::time_point wall = Clock::now();
  double cpu = cpuMsNow();
  // Appends (wall ms, CPU ms) to `samples`.
  void stop(std::vector<std::pair<double, double>>& samples) const {
    samples.push_back({std::chrono::duration<double, std::milli>(Clock::now() - wall).count(), cpuMsNow() - cpu});
  }
};

// One stage's wall time (median and median absolute deviation) and CPU time (median), ms.
struct Timing {
  double median = 0.0, mad = 0.0, cpu = 0.0;
  nlohmann::json json() const { return {{"medianMs", median}, {"madMs", mad}, {"cpuMedianMs", cpu}}; }
  std::string text() const { return fmt::format("{:.2f} ± {:.2f} ({:.2f})", median, mad, cpu); }
};

Timing timing(const std::vector<std::pair<double, double>>& samples) {
  Timing t;
  std::vector<double> wall, cpu;
  for (const auto& [w, c] : samples) wall.push_back(w), cpu.push_back(c);
  t.median = median(wall);
  t.cpu = median(cpu);
  std::vector<double> dev;
  for (double w : wall) dev.push_back(std::abs(w - t.median));
  t.mad = median(dev);
  return t;
}

unsigned char uchar(char ch) { return static_cast<unsigned char>(ch); }

// Bytes the bake reads: the .gltf / .glb plus, for a .gltf, the external buffers and images its JSON names
// (data: URIs are inside the file already).
uint64_t sourceBytes(const fs::path& file) {
  std::error_code ec;
  uint64_t bytes = fs::file_size(file, ec);
  if (ec || file.extension() != ".gltf") return ec ? 0 : bytes;
  std::ifstream in(file);
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) return bytes;
  for (const char* key : {"buffers", "images"}) {
    if (!j.contains(key) || !j[key].is_array()) continue;
    for (const auto& item : j[key]) {
      if (!item.contains("uri") || !item["uri"].is_string()) continue;
      std::string uri = item["uri"].get<std::string>();
      if (uri.rfind("data:", 0) == 0) continue;
      std::string decoded;  // percent-decoding, as URIs in glTF files are
      for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(uchar(uri[i + 1])) &&
            std::isxdigit(uchar(uri[i + 2]))) {
          decoded += char(std::strtol(uri.substr(i + 1, 2).c_str(), nullptr, 16));
          i += 2;
        } else {
          decoded += uri[i];
        }
      }
      const uint64_t size = fs::file_size(file.parent_path() / decoded, ec);
      if (!ec) bytes += size;
    }
  }
  return bytes;
}

// One file's measurements.
struct AssetRow {
  std::string file;  // relative to the assets folder
  std::string error; // non-empty: skipped
  uint64_t sourceBytes = 0, packBytes = 0, quantizedPackBytes = 0, texelBytes = 0;
  // BC against RGBA8 textures (measureTextureEncodings); rgba8PackBytes 0: the file has no baked textures.
  uint64_t gpuTextureBytes = 0, rgba8PackBytes = 0, rgba8GpuTextureBytes = 0;
  double bcPsnr = 0.0, bcMaxError = 0.0;
  uint64_t trianglesIn = 0, trianglesAllLods = 0, vertices = 0;
  size_t meshes = 0, objects = 0, textures = 0, texturesResized = 0, lodLevels = 0;
  double maxRelativeLodError = 0.0;  // coarsest level's recorded error / mesh radius, max over meshes
  double maxQuantizationError = 0.0, maxRelativeQuantizationError = 0.0;
  std::vector<std::string> resizeNotes;
  Timing import, geometry, textureBake, write, load, upload, qWrite, qLoad, qUpload;
  // Host memory of loading besides the Scene (docs/pack-format.md, "Reading"): the largest section as stored,
  // the reader's largest decode buffer, the upload's staging buffer and all its transient host buffers.
  uint64_t largestSection = 0, readScratchBytes = 0, stagingBytes = 0, uploadHostBytes = 0;
  double bakeMs() const { return import.median + geometry.median + textureBake.median + write.median; }
};

// One measured run of the chain; appends each stage's time. Fills `row`'s sizes and errors on the way.
Status runOnce(const fs::path& file, const fs::path& scratch, const BenchBakeCommand& c, gpu::Device& device,
               AssetRow& row, std::vector<std::vector<std::pair<double, double>>>& samples) {
  auto t = StageTimer();
  Result<ImportedScene> imported = importGltfScene(file.string());
  if (!imported) return imported.error();
  t.stop(samples[0]);

  t = StageTimer();
  Result<Scene> scene = buildImportedScene(*imported);
  if (!scene) return scene.error();
  t.stop(samples[1]);

  t = StageTimer();
  TextureBakeOptions to;
  to.maxTextureSize = c.maxTextureSize;
  TextureBakeReport textureReport;
  if (Status s = bakeTextures(*imported, to, &scene.value(), &textureReport); !s) return s.error();
  t.stop(samples[2]);

  const std::string packPath = (scratch / "bench.vbp").string();
  t = StageTimer();
  PackWriteReport written;
  if (Status s = writePack(*scene, packPath, &written); !s) return s.error();
  t.stop(samples[3]);

  t = StageTimer();
  PackReadStats readStats;
  Result<Scene> loaded = readPack(packPath, &readStats);
  if (!loaded) return loaded.error();
  t.stop(samples[4]);

  t = StageTimer();
  {
    Result<GpuScene> gpuScene = uploadScene(device, *loaded);
    if (!gpuScene) return gpuScene.error();
    row.gpuTextureBytes = gpuScene->textureBytes;
    row.stagingBytes = gpuScene->stagingBytes;
    row.uploadHostBytes = gpuScene->uploadHostBytes;
  }
  t.stop(samples[5]);
  row.largestSection = readStats.largestSection;
  row.readScratchBytes = readStats.peakScratchBytes;

  PackWriteReport qWritten;
  if (c.quantize) {
    const std::string qPath = (scratch / "bench_q.vbp").string();
    PackWriteOptions po;
    po.quantize = true;
    t = StageTimer();
    if (Status s = writePack(*scene, qPath, po, &qWritten); !s) return s.error();
    t.stop(samples[6]);
    t = StageTimer();
    Result<Scene> q = readPack(qPath);
    if (!q) return q.error();
    t.stop(samples[7]);
    t = StageTimer();
    {
      Result<GpuScene> gpuScene = uploadScene(device, *q);
      if (!gpuScene) return gpuScene.error();
    }
    t.stop(samples[8]);
  }

  // Sizes and errors (the same every run).
  row.sourceBytes = sourceBytes(file);
  row.packBytes = written.fileBytes;
  row.quantizedPackBytes = qWritten.fileBytes;
  row.texelBytes = textureReport.texelBytes;
  row.meshes = scene->meshes.size();
  row.objects = scene->objects.size();
  row.textures = scene->textures.size();
  row.texturesResized = textureReport.notes.size();
  row.resizeNotes = textureReport.notes;
  row.trianglesIn = row.trianglesAllLods = row.vertices = 0;
  row.lodLevels = 0;
  row.maxRelativeLodError = 0.0;
  for (size_t i = 0; i < scene->meshes.size(); ++i) {
    const Mesh& m = scene->meshes[i];
    row.trianglesIn += imported->meshes[i].source.indices.size() / 3;
    row.vertices += m.vertices.size();
    for (size_t l = 0; l < m.lods.size(); ++l) row.trianglesAllLods += m.triangleCount(l);
    row.lodLevels = std::max(row.lodLevels, m.lods.size());
    const double radius = double(m.boundsSphere.w);
    if (radius > 0.0 && !m.lods.empty())
      row.maxRelativeLodError = std::max(row.maxRelativeLodError, double(m.lods.back().error) / radius);
  }
  row.maxQuantizationError = qWritten.quantization.maxPositionError;
  row.maxRelativeQuantizationError = qWritten.quantization.maxRelativePositionError;
  return {};
}

// The file's textures baked both ways: pack sizes, GPU texture bytes, and the BC pack's rendered image against
// the RGBA8 pack's. Both scenes go through serializePack + parsePack, as the packs on disk would.
Status measureTextureEncodings(const fs::path& file, const BenchBakeCommand& c, gpu::Device& device, AssetRow& row) {
  Result<ImportedScene> imported = importGltfScene(file.string());
  if (!imported) return imported.error();
  Result<Scene> built = buildImportedScene(*imported);
  if (!built) return built.error();
  std::optional<Scene> loaded[2];  // BC, RGBA8
  uint64_t packBytes[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    Scene scene = *built;
    TextureBakeOptions to;
    to.maxTextureSize = c.maxTextureSize;
    to.encoding = k == 0 ? TextureEncoding::Bc : TextureEncoding::Rgba8;
    if (Status s = bakeTextures(*imported, to, &scene); !s) return s.error();
    if (scene.textures.empty()) return {};
    Result<std::vector<uint8_t>> bytes = serializePack(scene);
    if (!bytes) return bytes.error();
    packBytes[k] = bytes->size();
    Result<Scene> back = parsePack(bytes->data(), bytes->size(), file.string());
    if (!back) return back.error();
    loaded[k] = std::move(back.value());
  }
  row.rgba8PackBytes = packBytes[1];
  row.rgba8GpuTextureBytes = 0;
  for (const TextureClass& cls : loaded[1]->textureClasses) row.rgba8GpuTextureBytes += cls.totalBytes();
  FrameResult frames[2];
  for (int k = 0; k < 2; ++k) {
    auto renderer = Renderer::create(device, *loaded[k], {.width = 384, .height = 384});
    if (!renderer) return renderer.error();
    Result<FrameResult> frame = (*renderer)->renderFrame(loaded[k]->defaultCamera, FrameOptions{});
    if (!frame) return frame.error();
    frames[k] = std::move(frame.value());
  }
  const ImageError e = compareColor(frames[0].color, frames[1].color);
  row.bcPsnr = e.psnr;
  row.bcMaxError = e.maxAbs;
  return {};
}

double mb(uint64_t bytes) { return double(bytes) / 1e6; }
// x per second from x per `ms` milliseconds (0 when nothing was measured).
double perSecond(double x, double ms) { return ms > 0.0 ? x / (ms * 1e-3) : 0.0; }

}  // namespace

int runBenchBake(const BenchBakeCommand& c) {
  if (c.maxTextureSize < 1 || c.maxTextureSize > 16384 || (c.maxTextureSize & (c.maxTextureSize - 1)) != 0) {
    std::fprintf(stderr, "visbuf bench-bake: --max-texture-size %u: must be a power of two in 1..16384\n",
                 c.maxTextureSize);
    return 2;
  }
  // The output folder before any work (bad input, exit 1): it exists and is writable, or can be created.
  if (Status s = checkOutputFolder("-o", c.output); !s) return fail(s.error());
  if (!fs::is_directory(c.assets))
    return fail({ErrorCode::FileNotFound, fmt::format("{}: not a folder (--assets)", c.assets)});
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(c.assets)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".gltf" || ext == ".glb")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) return fail({ErrorCode::FileNotFound, fmt::format("{}: no .gltf / .glb files", c.assets)});

  std::error_code ec;
  const fs::path out(c.output);
  for (const char* name : {"bench-bake.json", "bench-bake.md"})
    if (Status s = checkOutputs({{"-o", (out / name).string(), true}}); !s) return fail(s.error());
  fs::create_directories(out, ec);
  if (ec) return fail({ErrorCode::IoError, fmt::format("{}: cannot create the output folder", c.output)});
  // The packs of the runs go into a folder of this run's own (mkdtemp: new, empty, never a folder of the user's
  // that happens to have the same name), removed at the end.
  std::string scratchTemplate = (out / ".bench-bake-scratch.XXXXXX").string();
  if (::mkdtemp(scratchTemplate.data()) == nullptr)
    return fail({ErrorCode::IoError, fmt::format("{}: cannot create a scratch folder in it", c.output)});
  const fs::path scratch(scratchTemplate);
  struct RemoveScratch {
    fs::path path;
    ~RemoveScratch() {
      std::error_code e;
      fs::remove_all(path, e);
    }
  } removeScratch{scratch};

  auto devOptions = gpu::parseDeviceOption(c.device, {.validation = c.validation});
  if (!devOptions) return fail(devOptions.error());
  auto device = gpu::Device::create(*devOptions);
  if (!device) return fail(device.error());
  const std::string deviceName = (*device)->name();
  std::printf("visbuf bench-bake: %zu file(s) under %s, %u+%u runs each, textures capped at %u, device %s\n",
              files.size(), printable(c.assets).c_str(), c.warmup, c.repeats, c.maxTextureSize, deviceName.c_str());

  std::vector<AssetRow> rows;
  for (const fs::path& file : files) {
    AssetRow row;
    row.file = fs::relative(file, c.assets).string();
    std::vector<std::vector<std::pair<double, double>>> samples(9), discard(9);
    for (uint32_t run = 0; run < c.warmup + c.repeats; ++run) {
      Status s = runOnce(file, scratch, c, **device, row, run < c.warmup ? discard : samples);
      if (!s) {
        row.error = fmt::format("{}: {}", errorCodeName(s.error().code), s.error().message);
        break;
      }
    }
    if (!row.error.empty()) {
      std::printf("  %-60s skipped: %s\n", printable(row.file).c_str(), printable(row.error).c_str());
      rows.push_back(std::move(row));
      continue;
    }
    if (Status s = measureTextureEncodings(file, c, **device, row); !s) {
      row.error = fmt::format("{}: {}", errorCodeName(s.error().code), s.error().message);
      std::printf("  %-60s skipped: %s\n", printable(row.file).c_str(), printable(row.error).c_str());
      rows.push_back(std::move(row));
      continue;
    }
    Timing* stages[] = {&row.import, &row.geometry, &row.textureBake, &row.write, &row.load,
                        &row.upload, &row.qWrite,   &row.qLoad,       &row.qUpload};
    for (size_t i = 0; i < 9; ++i) *stages[i] = timing(samples[i]);
    std::printf("  %-60s %8llu tris  import %8.2f  geometry %8.2f  textures %8.2f  write %7.2f  load %7.2f  "
                "upload %7.2f ms  pack %.2f MB\n",
                printable(row.file).c_str(), static_cast<unsigned long long>(row.trianglesIn), row.import.median,
                row.geometry.median, row.textureBake.median, row.write.median, row.load.median, row.upload.median,
                mb(row.packBytes));
    // Loading's transient host memory: the read's decode scratch and the upload's buffers are never held
    // together (the read has finished when the upload starts), so the peak is the larger of the two.
    const uint64_t transient = std::max(row.readScratchBytes, row.uploadHostBytes);
    std::printf("  %-60s load memory: largest section %.3f MB, read scratch %.3f MB, upload staging %.3f MB "
                "(all upload host buffers %.3f MB): peak transient %.2fx the largest section\n",
                "", mb(row.largestSection), mb(row.readScratchBytes), mb(row.stagingBytes), mb(row.uploadHostBytes),
                row.largestSection ? double(transient) / double(row.largestSection) : 0.0);
    if (row.rgba8PackBytes)
      std::printf("  %-60s textures: pack %.2f MB (rgba8 %.2f MB), GPU %.2f MB (rgba8 %.2f MB), bc vs rgba8 image "
                  "PSNR %.1f dB, max %.3f\n",
                  "", mb(row.packBytes), mb(row.rgba8PackBytes), mb(row.gpuTextureBytes), mb(row.rgba8GpuTextureBytes),
                  row.bcPsnr, row.bcMaxError);
    std::fflush(stdout);
    rows.push_back(std::move(row));
  }

  // Totals over the files that baked (sums of the medians).
  AssetRow total;
  size_t baked = 0;
  for (const AssetRow& r : rows) {
    if (!r.error.empty()) continue;
    ++baked;
    total.sourceBytes += r.sourceBytes;
    total.packBytes += r.packBytes;
    total.quantizedPackBytes += r.quantizedPackBytes;
    total.trianglesIn += r.trianglesIn;
    total.import.median += r.import.median;
    total.import.cpu += r.import.cpu;
    total.geometry.median += r.geometry.median;
    total.geometry.cpu += r.geometry.cpu;
    total.textureBake.median += r.textureBake.median;
    total.textureBake.cpu += r.textureBake.cpu;
    total.write.median += r.write.median;
    total.write.cpu += r.write.cpu;
    total.load.median += r.load.median;
    total.load.cpu += r.load.cpu;
    total.upload.median += r.upload.median;
    total.upload.cpu += r.upload.cpu;
    total.qLoad.median += r.qLoad.median;
    total.qLoad.cpu += r.qLoad.cpu;
  }
  // The point of the pack: loading it against producing the same scene from the glTF file. "in memory" is what
  // `render --scene X.gltf` does (import + geometry, no texture pixels); "same content" adds the texture bake.
  const double fromGltfMs = total.import.median + total.geometry.median;
  const double fromGltfFullMs = fromGltfMs + total.textureBake.median;
  const double fromGltfCpuMs = total.import.cpu + total.geometry.cpu;
  const double fromGltfFullCpuMs = fromGltfCpuMs + total.textureBake.cpu;
  std::printf("total over %zu file(s): import + geometry %.1f ms (+ textures %.1f ms), pack load %.1f ms: "
              "%.1fx faster than import + geometry, %.1fx faster than import + geometry + textures "
              "(CPU time: %.1fx, %.1fx)\n",
              baked, fromGltfMs, total.textureBake.median, total.load.median,
              total.load.median > 0 ? fromGltfMs / total.load.median : 0.0,
              total.load.median > 0 ? fromGltfFullMs / total.load.median : 0.0,
              total.load.cpu > 0 ? fromGltfCpuMs / total.load.cpu : 0.0,
              total.load.cpu > 0 ? fromGltfFullCpuMs / total.load.cpu : 0.0);

  const std::string date = utcNow();
  nlohmann::json j;
  stampInvocation(j, deviceName);
  j["date"] = date;
  j["repeats"] = c.repeats;
  j["warmup"] = c.warmup;
  j["maxTextureSize"] = c.maxTextureSize;
  j["times"] = "median and median absolute deviation over the repeats, ms";
  nlohmann::json rj = nlohmann::json::array();
  for (const AssetRow& r : rows) {
    nlohmann::json x = {{"file", r.file}};
    if (!r.error.empty()) {
      x["skipped"] = r.error;
      rj.push_back(x);
      continue;
    }
    x["sourceBytes"] = r.sourceBytes;
    x["packBytes"] = r.packBytes;
    x["meshes"] = r.meshes;
    x["objects"] = r.objects;
    x["vertices"] = r.vertices;
    x["trianglesIn"] = r.trianglesIn;
    x["trianglesAllLods"] = r.trianglesAllLods;
    x["lodLevelsMax"] = r.lodLevels;
    x["maxRelativeLodError"] = r.maxRelativeLodError;
    x["textures"] = {{"count", r.textures}, {"texelBytes", r.texelBytes}, {"resized", r.resizeNotes},
                     {"gpuBytes", r.gpuTextureBytes}};
    if (r.rgba8PackBytes) {
      x["textures"]["rgba8"] = {{"packBytes", r.rgba8PackBytes}, {"gpuBytes", r.rgba8GpuTextureBytes}};
      // JSON has no infinity: identical images give psnrDb null.
      x["textures"]["bcVsRgba8Image"] = {
          {"psnrDb", std::isfinite(r.bcPsnr) ? nlohmann::json(r.bcPsnr) : nlohmann::json()}, {"maxAbs", r.bcMaxError}};
    }
    x["import"] = r.import.json();
    x["geometry"] = r.geometry.json();
    x["textureBake"] = r.textureBake.json();
    x["write"] = r.write.json();
    x["load"] = r.load.json();
    x["upload"] = r.upload.json();
    x["loadMemory"] = {{"largestSectionBytes", r.largestSection}, {"readScratchBytes", r.readScratchBytes},
                       {"stagingBytes", r.stagingBytes}, {"uploadHostBytes", r.uploadHostBytes}};
    x["geometryTrianglesPerSecond"] = perSecond(double(r.trianglesIn), r.geometry.median);
    x["geometryTrianglesPerCpuSecond"] = perSecond(double(r.trianglesIn), r.geometry.cpu);
    x["bakeTrianglesPerSecond"] = perSecond(double(r.trianglesIn), r.bakeMs());
    x["bakeSourceMBPerSecond"] = perSecond(mb(r.sourceBytes), r.bakeMs());
    x["loadMBPerSecond"] = perSecond(mb(r.packBytes), r.load.median);
    x["loadVsImportGeometry"] = r.load.median > 0 ? (r.import.median + r.geometry.median) / r.load.median : 0.0;
    if (c.quantize) {
      x["quantized"] = {{"packBytes", r.quantizedPackBytes},
                        {"write", r.qWrite.json()},
                        {"load", r.qLoad.json()},
                        {"upload", r.qUpload.json()},
                        {"maxPositionError", r.maxQuantizationError},
                        {"maxRelativePositionError", r.maxRelativeQuantizationError}};
    }
    rj.push_back(x);
  }
  j["rows"] = rj;
  j["total"] = {{"files", baked},
                {"skipped", rows.size() - baked},
                {"sourceBytes", total.sourceBytes},
                {"packBytes", total.packBytes},
                {"trianglesIn", total.trianglesIn},
                {"importMs", total.import.median},
                {"geometryMs", total.geometry.median},
                {"textureBakeMs", total.textureBake.median},
                {"writeMs", total.write.median},
                {"loadMs", total.load.median},
                {"uploadMs", total.upload.median},
                {"loadVsImportGeometry", total.load.median > 0 ? fromGltfMs / total.load.median : 0.0},
                {"loadVsImportGeometryTextures", total.load.median > 0 ? fromGltfFullMs / total.load.median : 0.0},
                {"cpuMs", {{"import", total.import.cpu}, {"geometry", total.geometry.cpu},
                           {"textureBake", total.textureBake.cpu}, {"write", total.write.cpu},
                           {"load", total.load.cpu}, {"upload", total.upload.cpu}}},
                {"loadVsImportGeometryCpu", total.load.cpu > 0 ? fromGltfCpuMs / total.load.cpu : 0.0},
                {"loadVsImportGeometryTexturesCpu", total.load.cpu > 0 ? fromGltfFullCpuMs / total.load.cpu : 0.0}};

  // bench-bake.md
  std::string md = fmt::format("`{}`\n\n", c.commandLine);
  md += fmt::format(
      "{}, {}; {} warm-up + {} measured runs per file, times in ms as wall-clock median ± median absolute "
      "deviation (process CPU time median in brackets: on a machine shared with other work the wall time grows "
      "with the contention, the CPU time does not); textures capped at {}. tris = triangles imported (LOD 0 "
      "before optimisation); ktri/s = thousand tris per second of geometry time, wall (CPU); bake MB/s = source "
      "bytes (glTF + its buffers and images) / (import + geometry + textures + write); "
      "load MB/s = pack bytes / load time; ×glTF = (import + geometry) / load; LOD err = the coarsest level's "
      "recorded error / mesh radius (max over meshes); resized = textures resized (non-power-of-two or over the "
      "cap) / textures.\n\n",
      deviceName, date, c.warmup, c.repeats, c.maxTextureSize);
  md += "| file | tris | import | geometry | ktri/s | textures | resized | write | bake MB/s | pack MB | load | "
        "load MB/s | ×glTF | upload | LOD err |";
  std::string sep = "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";
  if (c.quantize) {
    md += " q pack MB | q load | q upload | q max err (rel.) |";
    sep += "---|---|---|---|";
  }
  md += "\n" + sep + "\n";
  for (const AssetRow& r : rows) {
    if (!r.error.empty()) continue;
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {}/{} | {} | {:.1f} | {:.3f} | {} | {:.0f} | {:.1f} | {} | "
                      "{:.3g} |",
                      r.file, r.trianglesIn, r.import.text(), r.geometry.text(),
                      fmt::format("{:.1f} ({:.1f})", perSecond(double(r.trianglesIn), r.geometry.median) / 1e3,
                                  perSecond(double(r.trianglesIn), r.geometry.cpu) / 1e3),
                      r.textureBake.text(),
                      r.texturesResized, r.textures, r.write.text(), perSecond(mb(r.sourceBytes), r.bakeMs()),
                      mb(r.packBytes), r.load.text(), perSecond(mb(r.packBytes), r.load.median),
                      r.load.median > 0 ? (r.import.median + r.geometry.median) / r.load.median : 0.0,
                      r.upload.text(), r.maxRelativeLodError);
    if (c.quantize)
      md += fmt::format(" {:.3f} | {} | {} | {:.3g} ({:.2g}) |", mb(r.quantizedPackBytes), r.qLoad.text(),
                        r.qUpload.text(), r.maxQuantizationError, r.maxRelativeQuantizationError);
    md += "\n";
  }
  // Textures: what BC saves against RGBA8 and what it costs in the image.
  bool anyTextures = false;
  for (const AssetRow& r : rows) anyTextures |= r.error.empty() && r.rgba8PackBytes > 0;
  if (anyTextures) {
    md += "\nTextures, BC (the default) against RGBA8 (`bake --textures rgba8`): pack and GPU texture bytes, and the "
          "BC pack's image against the RGBA8 pack's (default camera, 384x384, visbuf path; upload above includes "
          "the BC texture classes).\n\n| file | pack MB | rgba8 pack MB | GPU texture MB | rgba8 GPU texture MB | "
          "PSNR | max |\n|---|---|---|---|---|---|---|\n";
    for (const AssetRow& r : rows) {
      if (!r.error.empty() || r.rgba8PackBytes == 0) continue;
      md += fmt::format("| {} | {:.3f} | {:.3f} | {:.3f} | {:.3f} | {} | {:.3f} |\n", r.file, mb(r.packBytes),
                        mb(r.rgba8PackBytes), mb(r.gpuTextureBytes), mb(r.rgba8GpuTextureBytes),
                        std::isfinite(r.bcPsnr) ? fmt::format("{:.1f} dB", r.bcPsnr) : std::string("identical"),
                        r.bcMaxError);
    }
  }
  md += fmt::format(
      "\nTotal over {} file(s): {:.1f} MB of glTF in, {} triangles, {:.2f} MB of packs out. Import {:.1f} ms + "
      "geometry {:.1f} ms + textures {:.1f} ms + write {:.1f} ms; pack load {:.1f} ms, upload {:.1f} ms. Loading "
      "the packs is **{:.1f}x** faster than importing and building the glTF files ({:.1f} ms, what `render --scene "
      "X.gltf` does) and {:.1f}x faster than producing the same content from them (with the texture bake, "
      "{:.1f} ms). In CPU time: import {:.1f} + geometry {:.1f} + textures {:.1f} ms against pack load {:.1f} ms: "
      "**{:.1f}x** and {:.1f}x.\n",
      baked, mb(total.sourceBytes), total.trianglesIn, mb(total.packBytes), total.import.median,
      total.geometry.median, total.textureBake.median, total.write.median, total.load.median, total.upload.median,
      total.load.median > 0 ? fromGltfMs / total.load.median : 0.0, fromGltfMs,
      total.load.median > 0 ? fromGltfFullMs / total.load.median : 0.0, fromGltfFullMs, total.import.cpu,
      total.geometry.cpu, total.textureBake.cpu, total.load.cpu,
      total.load.cpu > 0 ? fromGltfCpuMs / total.load.cpu : 0.0,
      total.load.cpu > 0 ? fromGltfFullCpuMs / total.load.cpu : 0.0);
  bool anySkipped = false;
  for (const AssetRow& r : rows) {
    if (r.error.empty()) continue;
    md += fmt::format("{}- skipped `{}`: {}\n", anySkipped ? "" : "\nSkipped (import or bake failed):\n\n", r.file,
                      r.error);
    anySkipped = true;
  }

  if (Status s = writeTextFile((out / "bench-bake.md").string(), md); !s) return fail(s.error());
  if (Status s = writeJsonFile((out / "bench-bake.json").string(), j); !s) return fail(s.error());
  std::printf("wrote %s/bench-bake.{json,md}: %zu file(s) measured, %zu skipped\n", printable(c.output).c_str(), baked,
              rows.size() - baked);
  if ((*device)->validationEnabled() && (*device)->validationMessages() > 0) {
    std::fprintf(stderr, "visbuf bench-bake: %u validation message(s)\n", (*device)->validationMessages());
    return 3;
  }
  return 0;
}

}  // namespace visbuf::tools
