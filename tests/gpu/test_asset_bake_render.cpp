// Every glTF file of ../shared/assets end to end, as `visbuf bake` and `visbuf render` take it: import, build
// (meshoptimizer + LOD chain), texture bake, pack written to a temporary folder, read back, and both scenes
// (baked in memory, loaded from the pack) rendered by the visbuf and the forward path on the test device
// (lavapipe in CI) with validation on, at 160x120 from the scene's default camera; skinned scenes at time 0
// and at a later time of their clip.
//
// References and bounds:
//   - pack vs in memory: the pack stores the very vertices, indices, objects and camera the bake produced, so
//     the IDs must be identical and the colour within 1e-6 per channel (the same shader on the same inputs;
//     the bound leaves room only for a driver that is not bit-reproducible);
//   - visbuf vs forward (hardware interpolation): the bounds of tests/gpu/test_shading.cpp (same triangle at
//     every pixel on a CPU device, at most 0.1 % of the covered pixels elsewhere; where the triangle is the
//     same, every channel within 2e-3, mean within 5e-5, PSNR >= 80 dB);
//   - at least one covered pixel per frame (the default camera frames the scene);
//   - the Mesh_PrimitiveMode strips, fans and indexed lists cover the same pixels as its plain TRIANGLES file,
//     with the same colour within the visbuf-vs-forward bound.
// Files known to be bad must fail with a precise message instead: AssimpBadData's BoxWithInfinites (infinite
// vertex data) and the Mesh_PrimitiveMode files that hold only points or lines ("no triangle geometry");
// AssimpBadData's BoxBadNormals bakes with its zero-length normals replaced, and a warning saying so.
#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../unit/temp_dir_test.h"
#include "../unit/test_assets.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_writer.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/asset/texture_bake.h"
#include "gpu_test_util.h"

using namespace visbuf;
namespace fs = std::filesystem;

namespace {

constexpr uint32_t kWidth = 160, kHeight = 120;
constexpr double kPackMaxAbs = 1e-6;  // pack-loaded vs in-memory colour, per channel
// visbuf vs forward: the Shading.* bounds (tests/gpu/test_shading.cpp: the forward path is the device's
// interpolation, so the share of visibly differing pixels is bounded, not the largest difference; the H200 differs
// by up to 6.6e-3 on CesiumMan's skin), and PSNR above 80 dB on lavapipe, whose interpolation is exact to rgba16f
// rounding, and above the Shading.* 65 dB on a GPU (H100: BrainStem 79.5 dB, max 5.9e-3).
constexpr double kMeanAbs = 5e-5;
constexpr double kMaxDifferingShare = 5e-3;  // of the covered pixels, more than 1/255 apart
constexpr double kMinPsnrCpu = 80.0, kMinPsnrGpu = 65.0;
constexpr double kSameMeshMaxAbs = 2e-3;  // one visbuf frame against another of the same mesh, files apart
// Textured scenes: the shading pass picks mip levels from analytic derivatives, the forward reference from the
// rasteriser's 2x2-quad differences (Materials.MipSelectionMatchesExactLevelOfDetail: visbuf within 0.014 levels of
// the exact level of detail, forward within 0.19); where the two straddle a level the trilinear blend differs, and
// with nearest filtering a pixel near a texel edge may take the neighbouring texel. So the bound is on the mean,
// PSNR and the share of pixels that differ visibly, not on the largest difference (measured: AlphaBlendModeTest
// 78 dB; BoxTexturedNonPowerOfTwo, a high-contrast logo minified about 2 levels, 55.9 dB, mean 1.4e-4 and 1.06 %
// of the frame's pixels differing by more than 1/255). A wrong texel, level or slot everywhere fails them.
constexpr double kTexturedMeanAbs = 5e-4;
constexpr double kTexturedMinPsnr = 50.0;
constexpr double kTexturedMaxDiffering = 0.03;  // of all pixels, differing by more than 1/255
// Texture cap for the test's bake: texture pixels are not compared here (the shading does not sample them
// yet), but they are decoded, resized, mip-mapped, written and checksum-verified like any bake's.
constexpr uint32_t kTextureCap = 256;

// The files that must NOT bake, with a piece of the message that must say why.
const std::map<std::string, std::string>& expectedFailures() {
  static const std::map<std::string, std::string> failures = [] {
    std::map<std::string, std::string> m = {{"BoxWithInfinites.glb", "non-finite"}};
    // Mesh_PrimitiveMode_NN: 00-03 and 07-10 are POINTS / LINES / LINE_LOOP / LINE_STRIP (with and without
    // indices), skipped with a warning, which leaves no triangles; 04-06 and 11-15 are strips, fans, lists.
    for (int i : {0, 1, 2, 3, 7, 8, 9, 10})
      m[fmt::format("Mesh_PrimitiveMode_{:02}.gltf", i)] = "no triangle geometry";
    return m;
  }();
  return failures;
}

// Every .gltf / .glb under assets/ and the extra corpora (VISBUF_EXTRA_ASSETS), sorted per folder (so
// failures read the same on every run); a file of an extra corpus that assets/ also has is swept once.
std::vector<fs::path> assetFiles() {
  std::vector<fs::path> all;
  for (const fs::path& root : test::assetDirs()) {
    std::vector<fs::path> files;
    const bool extra = root != test::repoAssetsDir();
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      const std::string ext = entry.path().extension().string();
      if (extra && fs::exists(test::repoAssetsDir() / fs::relative(entry.path(), root))) continue;
      if (entry.is_regular_file() && (ext == ".gltf" || ext == ".glb")) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    all.insert(all.end(), files.begin(), files.end());
  }
  return all;
}

// Import + build + texture bake: what `visbuf bake` produces before it writes. The importer's warnings go to
// `warnings`.
Result<Scene> bakeInMemory(const fs::path& file, std::vector<std::string>& warnings) {
  GltfImportReport report;
  auto imported = importGltfScene(file.string(), {}, &report);
  warnings = report.warnings;
  if (!imported) return imported.error();
  auto scene = buildImportedScene(*imported);
  if (!scene) return scene.error();
  TextureBakeOptions to;
  to.maxTextureSize = kTextureCap;
  if (Status s = bakeTextures(*imported, to, &scene.value()); !s) {
    // A build without an image decoder (VISBUF_WITH_OIIO=OFF, a build fact) still checks everything but the texture
    // pixels: the materials keep their references unbaked, as `bake --no-textures` writes them. With one, any error
    // (Unsupported included) is the bake's failure.
    if (test::kWithOiio || s.error().code != ErrorCode::Unsupported) return s.error();
    std::printf("%s: texture pixels not baked: %s\n", file.filename().string().c_str(), s.error().message.c_str());
    scene->textures.clear();
    scene->textureClasses.clear();
    for (Material& m : scene->materials)
      for (TextureRef* t : textureSlots(m)) t->baked = -1;
  }
  return scene;
}

// The animation times a scene is rendered at: 0, and for skinned scenes 60 % into the first skinned
// object's clip (or 0.5 s when that clip is empty).
std::vector<double> renderTimes(const Scene& scene) {
  if (scene.skinnedObjects.empty()) return {0.0};
  const int32_t clip = scene.skinnedObjects.front().clip;
  double later = 0.5;
  if (clip >= 0 && size_t(clip) < scene.animations.size() && scene.animations[size_t(clip)].duration > 0.0)
    later = 0.6 * scene.animations[size_t(clip)].duration;
  return {0.0, later};
}

struct Frames {
  FrameResult visbuf, forward;
};

Frames renderBoth(Renderer& r, const Camera& cam, double time) {
  Frames f;
  FrameOptions fo;
  fo.lodErrorPixels = 0.0f;  // full detail: the forward path then draws exactly the same triangles
  fo.readIds = true;
  fo.animationTime = time;
  fo.path = RenderPath::Visbuf;
  auto vis = r.renderFrame(cam, fo);
  fo.path = RenderPath::Forward;
  auto fwd = r.renderFrame(cam, fo);
  EXPECT_TRUE(vis.ok()) << (vis.ok() ? "" : vis.error().message);
  EXPECT_TRUE(fwd.ok()) << (fwd.ok() ? "" : fwd.error().message);
  if (vis.ok()) f.visbuf = std::move(*vis);
  if (fwd.ok()) f.forward = std::move(*fwd);
  return f;
}

// visbuf vs forward on one frame, with the Shading.* bounds (looser for textured scenes, see above). Returns the
// covered pixel count.
size_t expectVisbufMatchesForward(const Frames& f, const std::string& name, bool textured) {
  size_t covered = 0, mismatch = 0;
  std::vector<float> visSame = f.visbuf.color, fwdSame = f.forward.color;
  for (size_t p = 0; p < f.visbuf.ids.size() / 2; ++p) {
    covered += f.visbuf.ids[2 * p] != 0;
    if (f.visbuf.ids[2 * p] != f.forward.ids[2 * p] || f.visbuf.ids[2 * p + 1] != f.forward.ids[2 * p + 1]) {
      ++mismatch;
      for (int c = 0; c < 4; ++c) visSame[p * 4 + c] = fwdSame[p * 4 + c] = 0.0f;
    }
  }
  const ImageError e = compareColor(visSame, fwdSame);
  std::printf("  %s: %zu px covered, %zu with another triangle; visbuf vs forward max %.2e, mean %.2e, PSNR %.1f dB\n",
              name.c_str(), covered, mismatch, e.maxAbs, e.meanAbs, e.psnr);
  if (f.visbuf.stats.cull.clusters.objects == 0) {  // (clusters: less the triangles of the clusters it culled)
    EXPECT_EQ(f.visbuf.stats.trianglesDrawn, f.forward.stats.trianglesDrawn) << name;
  } else {
    EXPECT_LE(f.visbuf.stats.trianglesDrawn, f.forward.stats.trianglesDrawn) << name;
  }
  if (test::testDevice().isCpu()) {
    EXPECT_EQ(mismatch, 0u) << name;
  } else {
    EXPECT_LE(double(mismatch), 1e-3 * double(covered)) << name;
  }
  if (textured) {
    EXPECT_LE(e.differingFraction, kTexturedMaxDiffering) << name;
  } else {
    EXPECT_LE(double(e.differing), kMaxDifferingShare * double(covered)) << name;
  }
  EXPECT_LE(e.meanAbs, textured ? kTexturedMeanAbs : kMeanAbs) << name;
  EXPECT_GE(e.psnr, textured ? kTexturedMinPsnr : test::testDevice().isCpu() ? kMinPsnrCpu : kMinPsnrGpu) << name;
  EXPECT_GT(covered, 0u) << name << ": the default camera must see the scene";
  return covered;
}

// The pack-loaded scene's frame against the in-memory one's: same IDs, colour within kPackMaxAbs.
void expectSameFrame(const FrameResult& pack, const FrameResult& memory, const std::string& name) {
  EXPECT_TRUE(pack.ids == memory.ids) << name << ": the pack-loaded scene shows other triangles";
  ASSERT_EQ(pack.color.size(), memory.color.size()) << name;
  double maxAbs = 0.0;
  for (size_t i = 0; i < pack.color.size(); ++i)
    maxAbs = std::max(maxAbs, double(std::abs(pack.color[i] - memory.color[i])));
  EXPECT_LE(maxAbs, kPackMaxAbs) << name << ": pack-loaded vs in-memory colour";
}

// Round trip: the pack gives back the baked meshes exactly (vertices byte for byte, every LOD's indices).
void expectSameGeometry(const Scene& pack, const Scene& memory) {
  ASSERT_EQ(pack.meshes.size(), memory.meshes.size());
  for (size_t i = 0; i < memory.meshes.size(); ++i) {
    const Mesh& a = pack.meshes[i];
    const Mesh& b = memory.meshes[i];
    ASSERT_EQ(a.vertices.size(), b.vertices.size()) << "mesh " << i;
    EXPECT_TRUE(std::memcmp(a.vertices.data(), b.vertices.data(), b.vertices.size() * sizeof(gpu::Vertex)) == 0)
        << "mesh " << i << ": vertices differ after the round trip";
    EXPECT_EQ(a.indices, b.indices) << "mesh " << i;
    ASSERT_EQ(a.lods.size(), b.lods.size()) << "mesh " << i;
    for (size_t l = 0; l < b.lods.size(); ++l) {
      EXPECT_EQ(a.lods[l].firstIndex, b.lods[l].firstIndex) << "mesh " << i << " LOD " << l;
      EXPECT_EQ(a.lods[l].indexCount, b.lods[l].indexCount) << "mesh " << i << " LOD " << l;
      EXPECT_EQ(a.lods[l].error, b.lods[l].error) << "mesh " << i << " LOD " << l;
    }
  }
}

// Round trip with --quantize (in memory): same indices; every decoded position within the mesh's reported max
// error, and within half a 16-bit step of the mesh's box (|extent| / 2 / 65535, plus float rounding of the
// decode: 1e-6 of the largest coordinate) -- an independent bound on the writer's own measurement.
void expectQuantizedRoundTrip(const Scene& memory, const std::string& name) {
  PackWriteOptions po;
  po.quantize = true;
  PackWriteReport report;
  auto bytes = serializePack(memory, po, &report);
  ASSERT_TRUE(bytes.ok()) << bytes.error().message;
  auto q = parsePack(bytes->data(), bytes->size(), name + " (quantised)");
  ASSERT_TRUE(q.ok()) << q.error().message;
  ASSERT_EQ(q->meshes.size(), memory.meshes.size());
  for (size_t i = 0; i < memory.meshes.size(); ++i) {
    const Mesh& a = q->meshes[i];
    const Mesh& b = memory.meshes[i];
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    EXPECT_EQ(a.indices, b.indices) << "mesh " << i;
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t v = 0; v < b.vertices.size(); ++v) {
      lo = glm::min(lo, glm::dvec3(b.position(v)));
      hi = glm::max(hi, glm::dvec3(b.position(v)));
    }
    const glm::dvec3 extent = hi - lo;
    const glm::dvec3 magnitude = glm::max(glm::abs(lo), glm::abs(hi));
    const double halfStep =
        0.5 * glm::length(extent) / 65535.0 + 1e-6 * std::max({magnitude.x, magnitude.y, magnitude.z});
    double maxError = 0.0;
    for (uint32_t v = 0; v < b.vertices.size(); ++v)
      maxError = std::max(maxError, glm::length(glm::dvec3(a.position(v)) - glm::dvec3(b.position(v))));
    EXPECT_LE(maxError, double(report.quantization.meshMaxPositionError[i]) * (1.0 + 1e-6) + 1e-12)
        << "mesh " << i << ": decoded positions beyond the reported error";
    EXPECT_LE(maxError, halfStep) << "mesh " << i << ": more than half a 16-bit step of the mesh's box";
  }
}

class AssetBakeRender : public test::GpuFixture<test::TempDirTest> {};

}  // namespace

TEST_F(AssetBakeRender, EveryAssetBakesToAPackAndRendersLikeItsInMemoryBake) {
  const auto start = std::chrono::steady_clock::now();
  size_t rendered = 0, rejected = 0;
  std::set<std::string> failedAsExpected;
  std::map<std::string, FrameResult> primitiveModes;  // Mesh_PrimitiveMode_NN.gltf -> its visbuf frame
  for (const fs::path& file : assetFiles()) {
    const std::string name = file.string();
    SCOPED_TRACE(name);
    std::vector<std::string> warnings;
    auto memory = bakeInMemory(file, warnings);
    const auto bad = expectedFailures().find(file.filename().string());
    if (bad != expectedFailures().end()) {
      ASSERT_FALSE(memory.ok()) << name << " must be rejected";
      EXPECT_EQ(memory.error().code, ErrorCode::MalformedInput) << memory.error().message;
      EXPECT_NE(memory.error().message.find(bad->second), std::string::npos)
          << "the message must say why (" << bad->second << "): " << memory.error().message;
      EXPECT_NE(memory.error().message.find(file.filename().string()), std::string::npos)
          << "the message must name the file: " << memory.error().message;
      std::printf("%s: rejected as expected: %s\n", name.c_str(), memory.error().message.c_str());
      failedAsExpected.insert(file.filename().string());
      ++rejected;
      continue;
    }
    ASSERT_TRUE(memory.ok()) << memory.error().message;
    if (file.filename() == "BoxBadNormals.glb") {  // repaired, and said so
      EXPECT_TRUE(std::any_of(warnings.begin(), warnings.end(), [](const std::string& w) {
        return w.find("zero-length normal(s) replaced") != std::string::npos;
      })) << "BoxBadNormals: its zero-length normals must be replaced with a warning";
    }

    const fs::path packPath = dir_ / (file.stem().string() + ".vbp");
    PackWriteReport written;
    const Status packed = writePack(*memory, packPath.string(), &written);
    ASSERT_TRUE(packed.ok()) << name << ": " << packed.error().message;
    auto pack = readPack(packPath.string());
    ASSERT_TRUE(pack.ok()) << pack.error().message;
    EXPECT_EQ(pack->objects.size(), memory->objects.size());
    EXPECT_EQ(pack->textures.size(), memory->textures.size());
    EXPECT_EQ(pack->skinnedObjects.size(), memory->skinnedObjects.size());
    expectSameGeometry(*pack, *memory);
    expectQuantizedRoundTrip(*memory, name);

    auto rMemory = Renderer::create(dev, *memory, {.width = kWidth, .height = kHeight});
    auto rPack = Renderer::create(dev, *pack, {.width = kWidth, .height = kHeight});
    ASSERT_TRUE(rMemory.ok()) << rMemory.error().message;
    ASSERT_TRUE(rPack.ok()) << rPack.error().message;
    std::printf("%s: %zu object(s), %llu triangles, %zu texture(s), pack %llu bytes\n", name.c_str(),
                memory->objects.size(), static_cast<unsigned long long>(memory->totalTriangles()),
                memory->textures.size(), static_cast<unsigned long long>(written.fileBytes));
    for (double t : renderTimes(*memory)) {
      const std::string frameName = fmt::format("{} t={:.2f}", name, t);
      SCOPED_TRACE(frameName);
      const Frames m = renderBoth(**rMemory, memory->defaultCamera, t);
      const Frames p = renderBoth(**rPack, pack->defaultCamera, t);
      if (HasFailure()) break;
      expectVisbufMatchesForward(m, frameName, !memory->textures.empty());
      if (t == 0.0 && file.filename().string().rfind("Mesh_PrimitiveMode_", 0) == 0)
        primitiveModes[file.filename().string()] = m.visbuf;
      expectSameFrame(p.visbuf, m.visbuf, frameName + " visbuf");
      expectSameFrame(p.forward, m.forward, frameName + " forward");
      if (HasFailure()) {
        test::saveOnFailure("asset_bake_render_" + file.stem().string(), m.visbuf, m.forward);
        break;
      }
    }
    ++rendered;
  }
  // Strips and fans (04, 05; indexed 11, 12) and the indexed lists (13-15) are the same quad as the plain
  // non-indexed TRIANGLES file (06), framed by the same camera: the same pixels covered, the same colour
  // (within the visbuf-vs-forward bound: normals are generated per file), whatever the triangle order.
  if (const auto ref = primitiveModes.find("Mesh_PrimitiveMode_06.gltf"); ref != primitiveModes.end()) {
    EXPECT_EQ(primitiveModes.size(), 8u) << "expected 8 Mesh_PrimitiveMode files with triangles";
    for (const auto& [file, frame] : primitiveModes) {
      size_t coverageDiffers = 0;
      double maxAbs = 0.0;
      for (size_t p = 0; p < frame.ids.size() / 2; ++p) {
        coverageDiffers += (frame.ids[2 * p] != 0) != (ref->second.ids[2 * p] != 0);
        for (int c = 0; c < 4; ++c)
          maxAbs = std::max(maxAbs, double(std::abs(frame.color[4 * p + c] - ref->second.color[4 * p + c])));
      }
      EXPECT_EQ(coverageDiffers, 0u) << file << " vs Mesh_PrimitiveMode_06.gltf (TRIANGLES)";
      EXPECT_LE(maxAbs, kSameMeshMaxAbs) << file << " vs Mesh_PrimitiveMode_06.gltf (TRIANGLES)";
    }
  }
  // Every expected failure was met (a renamed or removed file would otherwise leave a rule untested).
  for (const auto& [file, why] : expectedFailures()) {
    EXPECT_TRUE(failedAsExpected.count(file)) << file << " (" << why << ") was not found in the assets folder";
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%zu file(s) baked, packed and rendered, %zu rejected as expected, %.1f s\n", rendered, rejected,
              seconds);
  EXPECT_GT(rendered, 0u);
}
