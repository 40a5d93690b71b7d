// Material classification (passes/classify_pass.h): the classified shading must produce the ubershader's image, and
// its per-material counts must be those of the IDs. A 20 x 16 grid of small tilted quads at an odd resolution
// (333 x 171: partial tiles on the right and bottom), 340 generated materials (textured and untextured) assigned by
// hash, so that some materials have no pixels and many 8x8 tiles hold several materials; every fifth material is
// alpha-masked (the quads' vertex alpha runs 0..1, cutoff 0.5 cuts half of each) and double-sided.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "gpu_test_util.h"
#include "visbuf/render/frame_plan.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/scene.h"
#include "visbuf/shared/config.h"

namespace visbuf {
namespace {

// The quad grid with one default (untextured) material.
Scene quadGrid() {
  Scene s;
  MeshSource q;
  q.positions = {{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {-0.5f, 0.5f, 0}};
  q.normals.assign(4, glm::vec3(0, 0, 1));
  q.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  q.colors = {0x00ffffffu, 0xffffffffu, 0xffffffffu, 0x00ffffffu};  // alpha 0 at x = -0.5, 1 at x = +0.5
  q.indices = {0, 1, 2, 0, 2, 3};
  s.meshes.push_back(buildMesh(q, {.maxLods = 1}).value());
  for (uint32_t i = 0; i < 20 * 16; ++i) {
    const double x = double(i % 20) - 9.5, y = double(i / 20) - 7.5;
    const glm::dmat4 t = glm::translate(glm::dmat4(1.0), glm::dvec3(x * 0.9, y * 0.9, 0.1 * double(i % 3))) *
                         glm::rotate(glm::dmat4(1.0), 0.3 * double(i % 5) - 0.6, glm::dvec3(0.3, 1.0, 0.2));
    s.objects.push_back({t, 0, 0});
  }
  s.materials.push_back(Material{});
  s.defaultCamera.position = {1.0, -2.0, 12.0};
  s.defaultCamera.target = {0.0, 0.0, 0.0};
  return s;
}

Scene classificationScene(uint32_t materials) {
  Scene s = quadGrid();
  EXPECT_TRUE(applyGeneratedMaterials(s, materials, 7).ok());
  for (uint32_t m = 0; m < materials; m += 5) {
    s.materials[m].alphaMode = AlphaMode::Mask;
    s.materials[m].alphaCutoff = 0.5f;
    s.materials[m].doubleSided = true;
  }
  return s;
}

GPU_TEST(Classification, ClassifiedShadingEqualsUbershader) {
  constexpr uint32_t kMaterials = 340;
  const Scene s = classificationScene(kMaterials);
  auto r = Renderer::create(dev, s, {.width = 160, .height = 96});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.readIds = true;
  fo.shading = ShadingMode::Classified;
  ASSERT_TRUE((*r)->renderFrame(s.defaultCamera, fo).ok());  // a frame at another size first: resize keeps it right
  const uint32_t w = 333, h = 171, tilesX = (w + 7) / 8, tilesY = (h + 7) / 8;
  ASSERT_TRUE((*r)->resize(w, h).ok());

  fo.shading = ShadingMode::Uber;
  auto uber = (*r)->renderFrame(s.defaultCamera, fo);
  ASSERT_TRUE(uber.ok()) << uber.error().message;
  EXPECT_EQ(uber->stats.shade.mode, ShadingMode::Uber);
  fo.shading = ShadingMode::Classified;
  for (int frame = 0; frame < 2; ++frame) {  // twice: the second frame's counts start from zero again
    auto cls = (*r)->renderFrame(s.defaultCamera, fo);
    ASSERT_TRUE(cls.ok()) << cls.error().message;
    const FrameStats& st = cls->stats;
    ASSERT_EQ(st.shade.mode, ShadingMode::Classified);
    EXPECT_EQ(cls->ids, uber->ids);
    EXPECT_EQ(st.coveredPixels, uber->stats.coveredPixels) << "each pixel shaded by exactly one material dispatch";

    // The reference counts, from the IDs on the CPU: pixels per material and the distinct (tile, material) pairs.
    std::vector<uint32_t> pixels(kMaterials, 0), tiles(kMaterials, 0);
    std::set<std::pair<uint32_t, uint32_t>> pairs;
    std::vector<std::set<uint32_t>> tileMaterials(size_t(tilesX) * tilesY);
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const uint32_t object = uber->ids[2 * (size_t(y) * w + x)];
        if (object == 0) continue;
        const uint32_t m = s.objects[object - 1].material;
        ++pixels[m];
        tileMaterials[(y / 8) * tilesX + x / 8].insert(m);
      }
    size_t pairCount = 0, mostInOneTile = 0;
    for (const auto& t : tileMaterials) {
      for (uint32_t m : t) ++tiles[m];
      pairCount += t.size();
      mostInOneTile = std::max(mostInOneTile, t.size());
    }
    const uint32_t present = uint32_t(std::count_if(pixels.begin(), pixels.end(), [](uint32_t n) { return n > 0; }));
    uint32_t maskedPresent = 0;
    for (uint32_t m = 0; m < kMaterials; m += 5) maskedPresent += pixels[m] > 0;
    // The scene exercises what it is meant to: unused materials, tiles of several materials, masked materials.
    ASSERT_LT(present, kMaterials);
    ASSERT_GE(mostInOneTile, 3u);
    ASSERT_GT(maskedPresent, 10u);
    EXPECT_EQ(st.shade.materialPixels, pixels);
    EXPECT_EQ(st.shade.materialTiles, tiles);
    EXPECT_EQ(st.shade.materialsPresent, present);
    EXPECT_EQ(st.shade.classifiedTiles, pairCount);

    // Same pixels, same arithmetic (the material index only becomes a push constant): equal up to rounding.
    const ImageError e = compareColor(cls->color, uber->color);
    std::printf("classified vs uber (frame %d): %u of %u materials present, %zu pairs over %u tiles (up to %zu "
                "materials a tile), max diff %.2e, PSNR %.1f dB\n",
                frame, present, kMaterials, pairCount, tilesX * tilesY, mostInOneTile, e.maxAbs, e.psnr);
    EXPECT_LE(e.maxAbs, 1e-3);  // (measured: 0 on lavapipe)
    EXPECT_EQ(e.differingFraction, 0.0);
  }
}

// An untextured scene (only the untextured classified pipeline) equals the ubershader too, with its one material's
// dispatch over several rows of CLASSIFY_DISPATCH_WIDTH workgroups, the last one partial; Auto resolves per device
// type, and the attribute record (the ubershader's variant) forces the ubershader.
GPU_TEST(Classification, UntexturedAutoAndAttributes) {
  const Scene s = quadGrid();
  auto r = Renderer::create(dev, s, {.width = 161, .height = 97});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.readIds = true;
  fo.shading = ShadingMode::Uber;
  auto uber = (*r)->renderFrame(s.defaultCamera, fo);
  ASSERT_TRUE(uber.ok());
  fo.shading = ShadingMode::Classified;
  auto cls = (*r)->renderFrame(s.defaultCamera, fo);
  ASSERT_TRUE(cls.ok());
  EXPECT_EQ(cls->ids, uber->ids);
  EXPECT_EQ(compareColor(cls->color, uber->color).maxAbs, 0.0);
  uint32_t covered = 0;
  for (size_t p = 0; p < cls->ids.size(); p += 2) covered += cls->ids[p] != 0;
  EXPECT_GT(covered, 0u);
  EXPECT_EQ(cls->stats.shade.materialsPresent, 1u);
  EXPECT_EQ(cls->stats.shade.materialPixels, std::vector<uint32_t>{covered});
  ASSERT_EQ(cls->stats.shade.materialTiles.size(), 1u);
  EXPECT_GT(cls->stats.shade.materialTiles[0], CLASSIFY_DISPATCH_WIDTH);
  EXPECT_NE(cls->stats.shade.materialTiles[0] % CLASSIFY_DISPATCH_WIDTH, 0u);
  fo = {};
  auto f = (*r)->renderFrame(s.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  // Auto: the device type's default, except on a CPU device after frames that showed something in most pixels
  // (FrameHistory::mostlyCovered; the frames before this one covered `covered` pixels).
  const bool mostlyCovered = double(covered) >= kUberFromCoverage * 161.0 * 97.0;
  EXPECT_EQ(f->stats.shade.mode, dev.isCpu() && mostlyCovered ? ShadingMode::Uber : defaultShading(dev));
  fo.shading = ShadingMode::Classified;
  fo.readAttributes = true;
  f = (*r)->renderFrame(s.defaultCamera, fo);
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->stats.shade.mode, ShadingMode::Uber);
}

// Covered-pixel shading (covered_pixels.comp, then one thread per listed pixel): the ubershader's image exactly, at a
// size with partial tiles and more covered pixels than one dispatch row takes, after a resize, and for a frame that
// shows nothing (no pixel listed: the cleared background).
GPU_TEST(Classification, CoveredPixelsEqualUbershader) {
  const Scene s = classificationScene(40);
  auto r = Renderer::create(dev, s, {.width = 160, .height = 96});
  ASSERT_TRUE(r.ok()) << r.error().message;
  FrameOptions fo;
  fo.readIds = true;
  fo.shading = ShadingMode::Covered;
  ASSERT_TRUE((*r)->renderFrame(s.defaultCamera, fo).ok());
  ASSERT_TRUE((*r)->resize(333, 171).ok());
  Camera away = s.defaultCamera;
  away.target = away.position + (away.position - s.defaultCamera.target);  // looking the other way
  for (int view = 0; view < 2; ++view) {  // (an index: a range over {a, b} would iterate over copies)
    const Camera& cam = view == 0 ? s.defaultCamera : away;
    fo.shading = ShadingMode::Uber;
    auto uber = (*r)->renderFrame(cam, fo);
    fo.shading = ShadingMode::Covered;
    auto covered = (*r)->renderFrame(cam, fo);
    ASSERT_TRUE(uber.ok() && covered.ok());
    EXPECT_EQ(covered->stats.shade.mode, ShadingMode::Covered);
    EXPECT_EQ(covered->ids, uber->ids);
    size_t idPixels = 0;
    for (size_t i = 0; i < uber->ids.size(); i += 2) idPixels += uber->ids[i] != 0;
    EXPECT_EQ(uber->stats.coveredPixels, idPixels) << "the shading pass counts the pixels it shades";
    EXPECT_EQ(covered->stats.coveredPixels, idPixels);
    EXPECT_EQ(compareColor(covered->color, uber->color).maxAbs, 0.0);
    std::printf("covered pixels: %zu of %u, image identical to the ubershader's\n", idPixels, 333u * 171u);
    if (view == 0) {
      EXPECT_GT(idPixels, CLASSIFY_DISPATCH_WIDTH * SHADE_TILE_X * SHADE_TILE_Y) << "the dispatch must span several rows";
      EXPECT_NE(idPixels % (SHADE_TILE_X * SHADE_TILE_Y), 0u) << "the last workgroup must be partial";
      EXPECT_LT(idPixels, 333u * 171u) << "some pixels must show nothing";
    } else {
      EXPECT_EQ(idPixels, 0u) << "looking away: nothing listed";
    }
  }
}

}  // namespace
}  // namespace visbuf
