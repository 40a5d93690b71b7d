// visbuf bake: glTF 2.0 -> pack (engine/asset/pack_format.h). Import keeps the node hierarchy as instances
// (importGltfScene), every mesh is optimised with its LOD chain (buildImportedScene -> buildMesh), the scene
// is framed by a default camera, the materials' images are baked into size classes with mip chains, block-
// compressed by default (bakeTextures, on other threads while the meshes are built; --textures rgba8 stores them
// uncompressed, --texture-quality picks the BC colour fit; skipped with --no-textures), and the pack is written
// atomically (writePack: temporary file +
// rename). --quantize stores 20-byte quantised vertices (PackWriteOptions::quantize); the summary then reports
// the measured position / normal / uv error and the bytes saved, and the LOD errors as recorded (quantisation
// error included).
//
// Exit codes: 0 written; 1 bad input (unreadable / malformed glTF, a mesh that cannot be built, an image that
// is missing or cannot be decoded, a write that failed; an output folder that is missing or not writable, an
// output that is the input itself -- both checked before any work; the old OUT, if any, is untouched); 2 usage
// (option values out of range, refused by the option validators with the option's name).
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/task_group.h>
#include <unistd.h>

#include <bit>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "visbuf/core/file_read.h"
#include "cli_checks.h"
#include "commands.h"
#include "invocation.h"
#include "stats_output.h"

namespace visbuf::tools {

void addBakeCommand(CLI::App& app, BakeCommand& c) {
  CLI::App* sub = app.add_subcommand("bake", "bake a glTF 2.0 file (.gltf/.glb) into a visbuf pack (.vbp)");
  sub->add_option("input", c.input, "glTF 2.0 file to bake (.gltf or .glb)")->check(nonEmptyPath());
  sub->add_option("-o,--output", c.output, "pack to write (.vbp); replaced atomically")->check(nonEmptyPath());
  sub->add_option("--lod-count", c.lodCount,
                  fmt::format("LOD levels per mesh including the full mesh, 1..{}", MAX_LODS))
      ->check(unsignedIn(1, MAX_LODS))
      ->capture_default_str();
  sub->add_option("--lod-min-triangles", c.lodMinTriangles,
                  "stop a mesh's LOD chain once a level has this few triangles")
      ->check(unsignedIn(1, UINT32_MAX))
      ->capture_default_str();
  sub->add_flag("--quantize", c.quantize,
                "store quantised vertices: 16-bit positions over each mesh's box and uvs over its uv range "
                "(20 instead of 32 bytes a vertex; the error is measured and printed)");
  sub->add_option("--compression-level", c.compressionLevel,
                  "zstd level of the pack's sections (BC blocks, geometry streams), 1..19; 0 stores every section "
                  "raw. The loaded scene is the same at every level")
      ->check(unsignedIn(0, 19))
      ->capture_default_str();
  sub->add_option("--max-texture-size", c.maxTextureSize,
                  "largest baked texture side (power of two, 1..16384); larger images are downscaled")
      ->check(powerOfTwo(16384))
      ->capture_default_str();
  sub->add_option("--normal-map-size", c.normalMapSize,
                  "largest side of images used only as normal maps (power of two, 1..16384; default: "
                  "--max-texture-size): their larger mip levels are dropped")
      ->check(powerOfTwo(16384));
  sub->add_flag("--no-textures", c.noTextures, "do not bake texture pixels (materials keep their references)");
  sub->add_option("--textures", c.textures,
                  "texture storage: bc (block-compressed: BC1 colour, BC3 colour with alpha, BC4 occlusion, BC5 "
                  "normal maps) or rgba8 (uncompressed, 4 bytes a texel)")
      ->check(CLI::IsMember({"bc", "rgba8"}))
      ->capture_default_str();
  sub->add_option("--texture-quality", c.textureQuality,
                  "BC colour fit: fast (range fit), normal (cluster fit, ~5x slower), high (iterative cluster fit)")
      ->check(CLI::IsMember({"fast", "normal", "high"}))
      ->capture_default_str();
  sub->add_option("--allow-uri-root", c.allowUriRoots,
                  "also let the glTF's buffer / image uris point into this folder (repeatable; by default only "
                  "files inside the glTF's own folder are read: docs/security.md)")
      ->check(nonEmptyPath() & CLI::ExistingDirectory);
  sub->add_option("--max-image-pixels", c.maxImagePixels,
                  "refuse images whose header declares more pixels than this (width x height), before decoding")
      ->check(unsignedIn(1, uint64_t{1} << 40))
      ->capture_default_str();
  addImportBudgetOptions(*sub, c.maxInstances, c.maxImportMemory);
  addExtensionPolicyOptions(*sub, c.ignoreRequiredExtensions, c.strictImages);
  sub->add_option("--json", c.json, "also write the summary as JSON")->check(nonEmptyPath());
  sub->add_option("--threads", c.threads,
                  "threads building meshes and textures (0: all cores); the pack is the same byte for byte at any count")
      ->check(unsignedIn(0, 4096))
      ->capture_default_str();
}

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

int usage(const std::string& message) {
  std::fprintf(stderr, "visbuf bake: %s (see visbuf bake --help)\n", printable(message).c_str());
  return 2;
}
// An option value out of its range: bad input (exit 1), as CLI11's validators give.
int badValue(const std::string& message) {
  std::fprintf(stderr, "visbuf bake: %s (see visbuf bake --help)\n", printable(message).c_str());
  return 1;
}

int badInput(const Error& e) {
  std::fprintf(stderr, "visbuf bake: error (%s): %s\n", errorCodeName(e.code), printable(e.message).c_str());
  return 1;
}

// Progress on stderr: at most 4 updates per second plus the last one; rewritten in place on a terminal.
class Progress {
 public:
  Progress() : tty_(isatty(STDERR_FILENO) != 0) {}
  // `stage` names what was done: "built mesh", "baked texture".
  void update(const char* stage, size_t done, size_t total, const std::string& what) {
    std::lock_guard<std::mutex> lock(mutex_);  // meshes and textures are baked at the same time
    const auto now = Clock::now();
    if (done < total && now - last_ < std::chrono::milliseconds(250)) return;
    last_ = now;
    std::fprintf(stderr, "%sbake: %s %zu/%zu (%s)%s", tty_ ? "\r\033[K" : "", stage, done, total, printable(what).c_str(),
                 tty_ && done < total ? "" : "\n");
    std::fflush(stderr);
  }

 private:
  bool tty_;
  std::mutex mutex_;
  Clock::time_point last_{};
};

const char* colorSpaceName(ColorSpace c) { return c == ColorSpace::Srgb ? "sRGB" : "linear"; }

// "  textures: 5 (2 size classes, 27.9 MB with mips)" plus one line per class.
void printTextureSummary(const Scene& scene, const TextureBakeReport& report, bool skipped, nlohmann::json& json) {
  if (skipped) {
    std::printf("  textures: not baked (--no-textures)\n");
    return;
  }
  std::printf("  textures: %zu in %zu size class(es), %llu bytes with mips (%llu as RGBA8)\n", scene.textures.size(),
              scene.textureClasses.size(), static_cast<unsigned long long>(report.texelBytes),
              static_cast<unsigned long long>(report.rgba8Bytes));
  json["textures"] = {{"count", scene.textures.size()},
                      {"bytes", report.texelBytes},
                      {"rgba8Bytes", report.rgba8Bytes},
                      {"classes", nlohmann::json::array()}};
  for (size_t i = 0; i < scene.textureClasses.size(); ++i) {
    const TextureClass& cls = scene.textureClasses[i];
    std::printf("    class %zu: %ux%u %s %s, %u layer(s), %u mips, %zu bytes\n", i, cls.size, cls.size,
                colorSpaceName(cls.colorSpace), textureFormatName(cls.format), cls.layers, cls.mipCount,
                cls.texels.size());
    json["textures"]["classes"].push_back({{"size", cls.size},
                                           {"srgb", cls.colorSpace == ColorSpace::Srgb},
                                           {"format", textureFormatName(cls.format)},
                                           {"layers", cls.layers},
                                           {"mips", cls.mipCount},
                                           {"bytes", cls.texels.size()}});
  }
}

}  // namespace

int runBake(const BakeCommand& c) {
  if (c.input.empty()) return usage("missing the input glTF file");
  if (c.output.empty()) return usage("missing -o OUT (the pack to write)");
  if (c.lodCount < 1 || c.lodCount > MAX_LODS)
    return badValue(fmt::format("--lod-count {}: must be 1..{}", c.lodCount, MAX_LODS));
  if (c.lodMinTriangles < 1) return badValue("--lod-min-triangles must be at least 1");
  if (c.maxTextureSize < 1 || c.maxTextureSize > 16384 || !std::has_single_bit(c.maxTextureSize))
    return badValue(fmt::format("--max-texture-size {}: must be a power of two in 1..16384", c.maxTextureSize));
  if (c.textures != "bc" && c.textures != "rgba8")
    return badValue(fmt::format("--textures '{}': must be bc or rgba8", c.textures));
  if (c.textureQuality != "fast" && c.textureQuality != "normal" && c.textureQuality != "high")
    return badValue(fmt::format("--texture-quality '{}': must be fast, normal or high", c.textureQuality));
  // The output paths before any work (bad input, exit 1): their folders exist and are writable (nothing is
  // created yet), neither is the input itself (also through a symlink or a hard link), and they differ.
  noteInputFile(c.input, "the glTF to bake");
  std::vector<OutputFile> outputs = {{"-o", c.output}};
  if (!c.json.empty()) outputs.push_back({"--json", c.json});
  if (Status s = checkOutputs(outputs); !s) return badInput(s.error());
  if (isPackFile(c.input)) {
    return badInput(
        {ErrorCode::InvalidArgument, c.input + ": is already a visbuf pack; bake takes a .gltf/.glb file"});
  }
  const auto start = Clock::now();

  std::fprintf(stderr, "bake: importing %s\n", printable(c.input).c_str());
  GltfImportReport report;
  GltfImportOptions importOptions;
  importOptions.allowedUriRoots = c.allowUriRoots;
  importOptions.maxInstances = c.maxInstances;
  importOptions.maxMemoryBytes = c.maxImportMemory;
  importOptions.ignoreRequiredExtensions = c.ignoreRequiredExtensions;
  Result<ImportedScene> imported = importGltfScene(c.input, importOptions, &report);
  for (const std::string& w : report.warnings)
    std::fprintf(stderr, "visbuf bake: warning: %s\n", printable(w).c_str());
  if (!imported) return badInput(imported.error());
  // Nor may an output be one of the files the asset references (its buffers, read by the import, and its images,
  // read later by the texture bake or not at all with --no-textures: the importer notes them all as inputs).
  if (Status s = checkOutputs(outputs); !s) return badInput(s.error());
  const double importSeconds = secondsSince(start);

  MeshBuildOptions options;
  options.maxLods = c.lodCount;
  options.minTriangles = c.lodMinTriangles;
  // --threads: limits every oneTBB algorithm of this bake (mesh builds, texture bakes) while it lives; 0 keeps
  // oneTBB's default (all cores). The pack does not depend on it (buildImportedScene keeps the mesh order).
  std::optional<tbb::global_control> threadLimit;
  if (c.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t{c.threads});
  Progress progress;
  // Textures bake beside the meshes (they only read the import): on their own scene, whose materials are the
  // imported ones the build copies, so only the references' `baked` indices and the textures move across.
  Scene textureScene;
  textureScene.materials = imported->materials;
  TextureBakeReport textureReport;
  Status textureStatus;
  double textureSeconds = 0.0;
  tbb::task_group textureTask;
  if (!c.noTextures) {
    textureTask.run([&] {
      const auto textureStart = Clock::now();
      TextureBakeOptions textureOptions;
      textureOptions.maxTextureSize = c.maxTextureSize;
      textureOptions.maxImagePixels = c.maxImagePixels;
      textureOptions.dropUndecodableImages = !c.strictImages;
      textureOptions.maxNormalMapSize = c.normalMapSize;
      textureOptions.encoding = c.textures == "rgba8" ? TextureEncoding::Rgba8 : TextureEncoding::Bc;
      textureOptions.quality = c.textureQuality == "high"     ? TextureQuality::High
                               : c.textureQuality == "normal" ? TextureQuality::Normal
                                                              : TextureQuality::Fast;
      textureStatus = bakeTextures(*imported, textureOptions, &textureScene, &textureReport,
                                   [&](size_t done, size_t total, const std::string& name) {
                                     progress.update("baked texture", done, total, name);
                                   });
      textureSeconds = secondsSince(textureStart);
    });
  }
  const auto buildStart = Clock::now();
  Result<Scene> scene = buildImportedScene(
      *imported, options,
      [&](size_t done, size_t total, const std::string& mesh) { progress.update("built mesh", done, total, mesh); });
  const double buildSeconds = secondsSince(buildStart);
  textureTask.wait();
  if (!scene) return badInput(scene.error());
  for (const std::string& note : textureReport.notes) std::fprintf(stderr, "bake: resized %s\n", printable(note).c_str());
  for (const std::string& w : textureReport.warnings)
    std::fprintf(stderr, "visbuf bake: warning: %s\n", printable(w).c_str());
  if (!textureStatus) return badInput(textureStatus.error());
  if (!c.noTextures && !imported->materials.empty()) {
    scene->materials = std::move(textureScene.materials);
    scene->textures = std::move(textureScene.textures);
    scene->textureClasses = std::move(textureScene.textureClasses);
  }

  std::fprintf(stderr, "bake: writing %s\n", printable(c.output).c_str());
  const auto writeStart = Clock::now();
  PackWriteReport written;
  PackWriteOptions writeOptions;
  writeOptions.quantize = c.quantize;
  writeOptions.compressionLevel = int(c.compressionLevel);
  if (Status s = writePack(*scene, c.output, writeOptions, &written); !s) return badInput(s.error());
  const PackQuantizationReport& q = written.quantization;
  const double writeSeconds = secondsSince(writeStart);
  const double totalSeconds = secondsSince(start);

  // Meshes that cannot be simplified as asked: buildMesh ends a chain early when a level would keep more than
  // minReduction of the previous one (meshoptimizer found nothing more to remove: topology, borders, seams).
  std::vector<bool> stalled(scene->meshes.size(), false);
  for (size_t i = 0; i < scene->meshes.size(); ++i) {
    const Mesh& m = scene->meshes[i];
    const uint32_t coarsest = m.triangleCount(m.lods.size() - 1);
    if (m.lods.size() < options.maxLods && coarsest > options.minTriangles) {
      stalled[i] = true;
      std::fprintf(stderr,
                   "visbuf bake: warning: mesh %zu '%s' cannot be simplified below %u triangles: its LOD chain ends "
                   "after %zu of %u level(s) (no simplification kept between 1 triangle and %.0f %% of them)\n",
                   i, printable(m.name).c_str(), coarsest, m.lods.size(), options.maxLods, 100.0 * options.minReduction);
    }
  }

  // Summary: per mesh, triangles in (the imported source) and out per LOD with its recorded error.
  nlohmann::json json;
  stampInvocation(json, "none (bake runs on the CPU)");
  json["input"] = c.input;
  json["output"] = c.output;
  std::printf("visbuf bake: %s -> %s\n", printable(c.input).c_str(), printable(c.output).c_str());
  std::vector<size_t> instances(scene->meshes.size(), 0);
  for (const Object& o : scene->objects) ++instances[o.mesh];
  uint64_t trianglesIn = 0, trianglesLod0 = 0, trianglesAllLods = 0;
  for (size_t i = 0; i < scene->meshes.size(); ++i) {
    const Mesh& m = scene->meshes[i];
    const uint64_t in = imported->meshes[i].source.indices.size() / 3;
    trianglesIn += in;
    trianglesLod0 += m.triangleCount(0);
    std::printf("  mesh %zu '%s': %zu instance(s), %zu vertices, %llu triangles in\n", i, printable(m.name).c_str(),
                instances[i], m.vertices.size(), static_cast<unsigned long long>(in));
    nlohmann::json jm = {{"name", m.name},
                         {"instances", instances[i]},
                         {"vertices", m.vertices.size()},
                         {"trianglesIn", in},
                         {"simplificationStalled", bool(stalled[i])},
                         {"lods", nlohmann::json::array()}};
    // The error recorded in the pack: quantised, the mesh's measured max position error is added.
    const double extra = q.enabled ? double(q.meshMaxPositionError[i]) : 0.0;
    for (size_t l = 0; l < m.lods.size(); ++l) {
      const uint32_t t = m.triangleCount(l);
      trianglesAllLods += t;
      const double error = double(m.lods[l].error) + extra;
      std::printf("    LOD %zu: %9u triangles (%5.1f %%)  error %.3g\n", l, t,
                  in ? 100.0 * t / double(in) : 0.0, error);
      jm["lods"].push_back({{"triangles", t}, {"error", error}});
    }
    json["meshes"].push_back(jm);
  }
  std::printf(
      "  total: %zu mesh(es), %zu object(s), %zu material(s); triangles in %llu, LOD 0 %llu, all LODs %llu\n",
      scene->meshes.size(), scene->objects.size(), scene->materials.size(),
      static_cast<unsigned long long>(trianglesIn), static_cast<unsigned long long>(trianglesLod0),
      static_cast<unsigned long long>(trianglesAllLods));
  printTextureSummary(*scene, textureReport, c.noTextures, json);
  std::string sections;
  for (const PackSectionInfo& s : written.sections) {
    sections += fmt::format("{}{} {}", sections.empty() ? "" : ", ", s.name, s.size);
    if (s.storedSize != s.size) sections += fmt::format(" (zstd {})", s.storedSize);
    json["sections"].push_back({{"name", s.name}, {"bytes", s.size}, {"storedBytes", s.storedSize}});
  }
  std::printf("  pack: %llu bytes (%s)\n", static_cast<unsigned long long>(written.fileBytes),
              sections.c_str());
  if (q.enabled) {
    std::printf("  quantization: %llu vertices, 20 instead of 32 bytes each; %lld bytes saved\n",
                static_cast<unsigned long long>(q.vertices), static_cast<long long>(q.bytesSaved));
    std::printf("    position error: max %.6g, RMS %.6g (mesh units); max %.6g, RMS %.6g of the mesh radius\n",
                q.maxPositionError, q.rmsPositionError, q.maxRelativePositionError, q.rmsRelativePositionError);
    std::printf("    normal error: max %.6g; uv error: max %.6g\n", q.maxNormalError, q.maxUvError);
    json["quantization"] = {{"vertices", q.vertices},
                            {"bytesSaved", q.bytesSaved},
                            {"maxPositionError", q.maxPositionError},
                            {"rmsPositionError", q.rmsPositionError},
                            {"maxRelativePositionError", q.maxRelativePositionError},
                            {"rmsRelativePositionError", q.rmsRelativePositionError},
                            {"maxNormalError", q.maxNormalError},
                            {"maxUvError", q.maxUvError}};
  } else {
    json["quantization"] = nullptr;
  }
  std::printf("  time: import %.3f s, build %.3f s, textures %.3f s (beside the build), write %.3f s, total %.3f s\n",
              importSeconds,
              buildSeconds, textureSeconds, writeSeconds, totalSeconds);
  json["objects"] = scene->objects.size();
  json["materials"] = scene->materials.size();
  json["trianglesIn"] = trianglesIn;
  json["trianglesLod0"] = trianglesLod0;
  json["bytes"] = written.fileBytes;
  json["seconds"] = {
      {"import", importSeconds}, {"build", buildSeconds}, {"textures", textureSeconds},
      {"write", writeSeconds},   {"total", totalSeconds}};
  if (!c.json.empty()) {
    if (Status s = writeJsonFile(c.json, json); !s) return badInput(s.error());
  }
  return 0;
}

}  // namespace visbuf::tools
