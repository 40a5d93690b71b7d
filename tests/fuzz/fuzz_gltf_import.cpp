// libFuzzer target: the glTF importer (engine/asset/gltf_import.h) on arbitrary .gltf / .glb bytes, then the
// mesh build of the scenes that import (buildImportedScene, validateScene). gltf_import.h promises that
// nothing in a file's contents can make the importer assert or crash.
//
// The importer reads files, so each input is written to one file in a private temporary folder created once
// per process (mkdtemp, removed at exit). The importer tells GLB from glTF JSON by the "glTF" magic, so one
// file name serves both. External URIs in the input resolve against that empty folder.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "fuzz_check.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/scene_bake.h"
#include "visbuf/scene/scene.h"

namespace {

// The import's memory budget: the default (4 GiB) is more than the fuzzer's -rss_limit_mb allows with ASan.
constexpr uint64_t kMaxMemoryBytes = uint64_t{256} << 20;

std::string g_dir;
std::string g_path;

void removeDir() {
  std::error_code ec;
  std::filesystem::remove_all(g_dir, ec);
}

void setUp() {
  std::string pattern = (std::filesystem::temp_directory_path() / "visbuf-fuzz-gltf-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    std::perror("mkdtemp");
    std::abort();
  }
  g_dir = pattern;
  g_path = g_dir + "/input.gltf";
  std::atexit(removeDir);
}

bool writeInput(const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(g_path.c_str(), "wb");
  if (!f) return false;
  const bool ok = (size == 0 || std::fwrite(data, 1, size, f) == size);
  return std::fclose(f) == 0 && ok;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  setUp();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace visbuf;
  if (!writeInput(data, size)) {
    std::perror(g_path.c_str());
    std::abort();
  }

  GltfImportOptions options;
  options.maxMemoryBytes = kMaxMemoryBytes;
  Result<ImportedScene> scene = importGltfScene(g_path, options);
  if (!scene) {
    VISBUF_FUZZ_CHECK(!scene.error().message.empty(), "importGltfScene: error without a message");
  } else {
    for (const ImportedMesh& m : scene->meshes) {
      VISBUF_FUZZ_CHECK(m.source.indices.size() % 3 == 0, "importGltfScene: index count not a multiple of 3");
      for (uint32_t i : m.source.indices)
        VISBUF_FUZZ_CHECK(i < m.source.positions.size(), "importGltfScene: index out of range");
    }
    for (const ImportedInstance& inst : scene->instances) {
      VISBUF_FUZZ_CHECK(inst.mesh < scene->meshes.size(), "importGltfScene: instance mesh out of range");
      VISBUF_FUZZ_CHECK(inst.material < scene->materials.size(), "importGltfScene: instance material out of range");
    }
    Result<Scene> built = buildImportedScene(*scene);
    if (built) {
      const Status valid = validateScene(*built);
      if (!valid) std::fprintf(stderr, "validateScene: %s\n", valid.error().message.c_str());
      VISBUF_FUZZ_CHECK(valid.ok(), "buildImportedScene gave a scene that fails validateScene()");
    } else {
      VISBUF_FUZZ_CHECK(!built.error().message.empty(), "buildImportedScene: error without a message");
    }
  }

  Result<MeshSource> mesh = importGltfMesh(g_path, options);
  if (!mesh) {
    VISBUF_FUZZ_CHECK(!mesh.error().message.empty(), "importGltfMesh: error without a message");
  } else {
    VISBUF_FUZZ_CHECK(mesh->normals.size() == mesh->positions.size(), "importGltfMesh: normals != positions");
    VISBUF_FUZZ_CHECK(mesh->indices.size() % 3 == 0, "importGltfMesh: index count not a multiple of 3");
    for (uint32_t i : mesh->indices)
      VISBUF_FUZZ_CHECK(i < mesh->positions.size(), "importGltfMesh: index out of range");
  }
  return 0;
}
