// EXT_mesh_gpu_instancing end to end: the gltfpack-style file with 4096 instances of tests/unit/
// instancing_fixture.h and its expanded twin (one node per instance), imported, baked (buildImportedScene) and
// rendered with the same camera: the same objects in the same order, so the decoded ID images must be equal
// pixel for pixel and the colour images bit for bit, on the visibility-buffer and the forward path.
#include <filesystem>
#include <fstream>
#include <random>
#include <set>

#include "../unit/instancing_fixture.h"
#include "gpu_test_util.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"

using namespace visbuf;

GPU_TEST(Instancing, GltfpackStyleFileRendersLikeExpandedNodes) {
  const test::InstancingFiles files = test::makeInstancingFiles({.instances = 4096});
  std::random_device rd;
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("visbuf_inst_" + std::to_string(rd()));
  std::filesystem::create_directories(dir);
  auto load = [&](const nlohmann::json& doc, const char* name) -> Result<Scene> {
    const std::string path = (dir / name).string();
    std::ofstream(path) << doc.dump();
    auto imported = importGltfScene(path);
    if (!imported) return imported.error();
    return buildImportedScene(*imported);
  };
  Result<Scene> instanced = load(files.instanced, "instanced.gltf");
  Result<Scene> expanded = load(files.expanded, "expanded.gltf");
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(instanced.ok()) << instanced.error().message;
  ASSERT_TRUE(expanded.ok()) << expanded.error().message;
  ASSERT_EQ(instanced->objects.size(), 4096u);
  ASSERT_EQ(expanded->objects.size(), 4096u);
  const uint32_t w = 320, h = 240;
  const Camera cam = instanced->defaultCamera;
  for (RenderPath path : {RenderPath::Visbuf, RenderPath::Forward}) {
    FrameOptions fo;
    fo.path = path;
    fo.readIds = true;
    auto ra = Renderer::create(dev, *instanced, {.width = w, .height = h});
    auto rb = Renderer::create(dev, *expanded, {.width = w, .height = h});
    ASSERT_TRUE(ra.ok() && rb.ok());
    auto a = (*ra)->renderFrame(cam, fo);
    auto b = (*rb)->renderFrame(cam, fo);
    ASSERT_TRUE(a.ok() && b.ok());
    size_t covered = 0, differentIds = 0;
    std::set<uint32_t> objects;
    for (size_t i = 0; i < a->ids.size(); i += 2) {
      covered += a->ids[i] != 0;
      if (a->ids[i] != 0) objects.insert(a->ids[i]);
      differentIds += a->ids[i] != b->ids[i] || a->ids[i + 1] != b->ids[i + 1];
    }
    const test::ImageError e = test::compareColor(a->color, b->color);
    std::printf("%s: 4096 instances vs 4096 nodes: %zu px covered, %zu objects visible, %zu px with other IDs, "
                "colour max %.2e\n",
                path == RenderPath::Visbuf ? "visbuf" : "forward", covered, objects.size(), differentIds, e.maxAbs);
    EXPECT_GT(covered, size_t(w) * h / 10);
    EXPECT_GT(objects.size(), 500u) << "a good part of the instances must be in view";
    EXPECT_EQ(differentIds, 0u);
    EXPECT_EQ(e.maxAbs, 0.0);
    test::saveOnFailure(path == RenderPath::Visbuf ? "instancing_visbuf" : "instancing_forward", *a, *b);
  }
}
