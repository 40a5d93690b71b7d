// glTF cameras rendered: each camera of a file (perspective with its aspect ratio and far plane, orthographic) draws
// the pixels a double-precision ray cast through the same camera covers, and visbuf draws what forward draws.
// Files: a generated one (always), and ../shared/assets/Cameras when VISBUF_EXTRA_ASSETS has it.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "gpu_test_util.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/render/pixel_judge.h"

using namespace visbuf;

namespace {

// Coverage by a CPU ray cast (double precision, every triangle of every object, LOD 0) at each pixel centre: hits in
// front of the camera within [near, far] along the view direction.
std::vector<uint8_t> castCoverage(const Scene& scene, const Camera& cam, uint32_t w, uint32_t h) {
  const FrameMath fm = computeFrameMath(cam, w, h);
  std::vector<uint8_t> covered(size_t(w) * h, 0);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const PixelRay ray = pixelRay(fm, x + 0.5, y + 0.5);
      for (const Object& o : scene.objects) {
        const Mesh& mesh = scene.meshes[o.mesh];
        for (uint32_t t = 0; t < mesh.triangleCount(0) && !covered[y * w + x]; ++t) {
          glm::dvec3 v[3];
          for (int k = 0; k < 3; ++k) {
            const glm::vec3 p = mesh.position(mesh.indices[mesh.lods[0].firstIndex + 3 * t + uint32_t(k)]);
            v[k] = glm::dvec3(o.transform * glm::dvec4(glm::dvec3(p), 1.0)) - cam.position;
          }
          auto hit = intersectTriangle(v, ray);
          if (!hit || hit->second.x < 0.0 || hit->second.y < 0.0 || hit->second.z < 0.0) continue;
          const double depth = glm::dot(ray.at(hit->first), fm.forward);
          covered[y * w + x] = depth >= cam.nearPlane && depth <= cam.farPlane;
        }
      }
    }
  return covered;
}

// Every camera of the file: coverage against the ray cast (pixels whose centre lies within 1e-6 of a triangle edge
// may go either way: at most 2 % of the covered ones, measured 0-1 on these files), visbuf IDs equal to forward's.
void checkFileCameras(gpu::Device& dev, const std::filesystem::path& path, size_t expectedCameras) {
  Result<ImportedScene> imported = importGltfScene(path.string());
  ASSERT_TRUE(imported.ok()) << imported.error().message;
  Result<Scene> scene = buildImportedScene(*imported);
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  ASSERT_EQ(scene->cameras.size(), expectedCameras);
  for (auto [w, h] : {std::pair{96u, 96u}, std::pair{128u, 72u}}) {
    auto renderer = Renderer::create(dev, *scene, {.width = w, .height = h});
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;
    for (size_t i = 0; i < scene->cameras.size(); ++i) {
      const Camera& cam = scene->cameras[i].camera;
      auto [vis, fwd] = test::renderBothPaths(**renderer, cam);
      ASSERT_TRUE(vis.ok() && fwd.ok());
      const std::vector<uint8_t> want = castCoverage(*scene, cam, w, h);
      size_t covered = 0, wrong = 0, pathsDiffer = 0;
      for (size_t p = 0; p < want.size(); ++p) {
        covered += want[p];
        wrong += (vis->ids[2 * p] != 0) != (want[p] != 0);
        pathsDiffer += vis->ids[2 * p] != fwd->ids[2 * p] || vis->ids[2 * p + 1] != fwd->ids[2 * p + 1];
      }
      std::printf("%s camera %zu (%s) %ux%u: %zu pixels covered by the ray cast, %zu differ, visbuf vs forward %zu\n",
                  path.filename().string().c_str(), i,
                  cam.projection == Projection::Orthographic ? "orthographic" : "perspective", w, h, covered, wrong,
                  pathsDiffer);
      EXPECT_GT(covered, 50u);
      EXPECT_LE(double(wrong), 0.02 * double(covered));
      EXPECT_EQ(pathsDiffer, 0u);
    }
  }
}

}  // namespace

// A generated file: a unit square and a tilted triangle; a perspective camera with aspectRatio 2 and a far plane that
// cuts the triangle, a rotated one without aspect or far, and an orthographic one with a non-square window, each on
// a node with scale (which glTF ignores for cameras).
class CameraFiles : public test::GpuTest {
 protected:
  void SetUp() override {
    test::GpuTest::SetUp();
    dir_ = std::filesystem::temp_directory_path() / ("visbuf_cameras_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
    test::GpuTest::TearDown();
  }
  std::filesystem::path dir_;
};

TEST_F(CameraFiles, GeneratedPerspectiveAspectAndOrthographic) {
  const float positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0,       // square (z = 0)
                             -0.5f, 0, -2, 0.5f, 0, -2, 0, 0.8f, -12};     // triangle reaching to z = -12
  const uint16_t indices[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 0};
  std::vector<uint8_t> bytes(sizeof(positions) + sizeof(indices));
  std::memcpy(bytes.data(), positions, sizeof(positions));
  std::memcpy(bytes.data() + sizeof(positions), indices, sizeof(indices));
  const double s = std::sin(0.2), c = std::cos(0.2);  // half of a 0.4 rad turn about +Y
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}}},
      {"buffers", {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(bytes)}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", sizeof(positions)}},
        {{"buffer", 0}, {"byteOffset", sizeof(positions)}, {"byteLength", 18}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 7}, {"type", "VEC3"}, {"min", {-1, -1, -12}},
         {"max", {1, 1, 0}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 9}, {"type", "SCALAR"}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"cameras",
       {{{"type", "perspective"}, {"perspective", {{"yfov", 0.5}, {"aspectRatio", 2.0}, {"znear", 0.5}, {"zfar", 9.0}}}},
        {{"type", "perspective"}, {"perspective", {{"yfov", 0.9}, {"znear", 0.1}}}},
        {{"type", "orthographic"}, {"orthographic", {{"xmag", 1.5}, {"ymag", 0.8}, {"znear", 0.0}, {"zfar", 14.0}}}}}},
      {"nodes",
       {{{"mesh", 0}},
        {{"camera", 0}, {"translation", {0.2, 0.1, 4.0}}, {"scale", {3.0, 3.0, 3.0}}},
        {{"camera", 1}, {"translation", {1.5, 0.5, 3.0}}, {"rotation", {0.0, s, 0.0, c}}},
        {{"camera", 2}, {"translation", {0.0, 0.0, 2.0}}, {"scale", {0.5, 2.0, 1.0}}}}},
      {"scenes", {{{"nodes", {0, 1, 2, 3}}}}},
      {"scene", 0}};
  const std::filesystem::path path = dir_ / "cameras.gltf";
  std::ofstream(path) << doc.dump();
  checkFileCameras(dev, path, 3);
}

GPU_EXTRA_ASSET_TEST(CameraAssets, KhronosCameras, "Cameras/glTF/Cameras.gltf") {
  checkFileCameras(test::testDevice(), asset, 2);
}
