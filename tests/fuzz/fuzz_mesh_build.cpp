// libFuzzer target: the mesh build (scene.h buildMesh: dedup, vertex cache / overdraw / fetch order, the LOD chain
// with its measured errors, meshlet order) and the cluster bounds (clusters.h lodClusters), on
//   - glTF / GLB bytes (first bytes "glTF" or "{"): importGltfMesh, then buildMesh;
//   - any other bytes: a mesh read straight from them (below), so that mutations reach the build's own worst cases
//     (coincident vertices, fans, stacked copies, slivers, huge triangles among small ones) without going through
//     the glTF syntax.
// Run with -timeout and -rss_limit_mb (scripts/fuzz.sh): a slow or hungry input is a finding, like a crash.
//
// Raw layout: byte 0 flags (bit 0: coordinates spread over 2^16 steps instead of 16, bit 1: one coordinate scaled
// by 1e6 (huge triangles), bit 2: add a second normal per vertex class), byte 1 vertex count / 4 (1..256 * 4),
// then 3 bytes per vertex (x, y, z; few distinct values, so coincidences are common), then the rest as indices
// (2 bytes each, modulo the vertex count); the index list is repeated so that an input of a few KB makes a mesh of
// tens of thousands of triangles.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "fuzz_check.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/scene/clusters.h"
#include "visbuf/scene/scene.h"

namespace {

constexpr uint64_t kMaxMemoryBytes = uint64_t{256} << 20;  // the import's budget, within -rss_limit_mb under ASan
constexpr size_t kMaxRawTriangles = 20000;                 // the raw mesh's size after repetition

std::string g_dir;
std::string g_path;

void removeDir() {
  std::error_code ec;
  std::filesystem::remove_all(g_dir, ec);
}

bool writeInput(const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(g_path.c_str(), "wb");
  if (!f) return false;
  const bool ok = (size == 0 || std::fwrite(data, 1, size, f) == size);
  return std::fclose(f) == 0 && ok;
}

visbuf::MeshSource rawMesh(const uint8_t* data, size_t size) {
  visbuf::MeshSource m;
  m.name = "raw";
  if (size < 2) return m;
  const uint8_t flags = data[0];
  const size_t vertices = (size_t(data[1]) + 1) * 4;
  size_t at = 2;
  for (size_t v = 0; v < vertices; ++v) {
    glm::vec3 p(0.0f);
    for (int k = 0; k < 3; ++k) {
      const uint8_t b = at < size ? data[at++] : uint8_t(v * 7 + k);
      p[k] = (flags & 1) ? float(b) * 257.0f / 65535.0f : float(b & 15) / 15.0f;
    }
    if (flags & 2) p.x *= 1e6f;
    m.positions.push_back(p);
    const bool flip = (flags & 4) && (v & 1);
    m.normals.push_back(flip ? glm::vec3(0, 0, -1) : glm::vec3(0, 0, 1));
  }
  std::vector<uint32_t> pattern;
  for (; at + 1 < size; at += 2) pattern.push_back(uint32_t(data[at] | data[at + 1] << 8) % uint32_t(vertices));
  pattern.resize(pattern.size() / 3 * 3);
  if (pattern.empty()) return m;
  while (m.indices.size() + pattern.size() <= 3 * kMaxRawTriangles) m.indices.insert(m.indices.end(), pattern.begin(), pattern.end());
  return m;
}

void checkMesh(const visbuf::MeshSource& source, const visbuf::Mesh& mesh) {
  using namespace visbuf;
  VISBUF_FUZZ_CHECK(!mesh.lods.empty() && !mesh.vertices.empty(), "buildMesh: no level or no vertex");
  VISBUF_FUZZ_CHECK(mesh.lods[0].firstIndex == 0 && mesh.lods[0].error == 0.0f, "buildMesh: LOD0 is not the full mesh");
  VISBUF_FUZZ_CHECK(mesh.lods[0].indexCount <= source.indices.size(), "buildMesh: LOD0 has more triangles than the source");
  uint32_t end = 0;
  float error = 0.0f;
  for (size_t l = 0; l < mesh.lods.size(); ++l) {
    const Lod& lod = mesh.lods[l];
    VISBUF_FUZZ_CHECK(lod.firstIndex == end && lod.indexCount > 0 && lod.indexCount % 3 == 0, "buildMesh: bad level range");
    VISBUF_FUZZ_CHECK(lod.error >= error && !(lod.error != lod.error), "buildMesh: errors not non-decreasing");
    error = lod.error;
    end += lod.indexCount;
    if (lodHasClusters(lod)) {
      const std::vector<gpu::ClusterData> clusters = lodClusters(mesh, l);
      VISBUF_FUZZ_CHECK(clusters.size() == lodClusterCount(lod), "lodClusters: wrong cluster count");
    }
  }
  VISBUF_FUZZ_CHECK(end == mesh.indices.size(), "buildMesh: levels do not cover the index buffer");
  for (uint32_t i : mesh.indices) VISBUF_FUZZ_CHECK(i < mesh.vertices.size(), "buildMesh: index out of range");
}

void build(const visbuf::MeshSource& source) {
  visbuf::Result<visbuf::Mesh> mesh = visbuf::buildMesh(source);
  if (mesh) {
    checkMesh(source, *mesh);
  } else {
    VISBUF_FUZZ_CHECK(!mesh.error().message.empty(), "buildMesh: error without a message");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  std::string pattern = (std::filesystem::temp_directory_path() / "visbuf-fuzz-mesh-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    std::perror("mkdtemp");
    std::abort();
  }
  g_dir = pattern;
  g_path = g_dir + "/input.gltf";
  std::atexit(removeDir);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace visbuf;
  const bool gltf = (size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T' && data[3] == 'F') ||
                    (size >= 1 && data[0] == '{');
  if (!gltf) {
    const MeshSource source = rawMesh(data, size);
    if (!source.indices.empty()) build(source);
    return 0;
  }
  if (!writeInput(data, size)) {
    std::perror(g_path.c_str());
    std::abort();
  }
  GltfImportOptions options;
  options.maxMemoryBytes = kMaxMemoryBytes;
  Result<MeshSource> source = importGltfMesh(g_path, options);
  if (!source) {
    VISBUF_FUZZ_CHECK(!source.error().message.empty(), "importGltfMesh: error without a message");
    return 0;
  }
  build(*source);
  return 0;
}
