// libFuzzer target: the KHR_draco_mesh_compression path of the glTF importer (engine/asset/gltf_draco.cpp) on
// arbitrary Draco streams. Each input is
//   byte 0-3:  point count P (u16) and face count F (u16) that the accessors declare;
//   byte 4:    the Draco attribute ids of POSITION (low nibble) and NORMAL (high nibble);
//   byte 5:    the indices accessor's component type (0: UNSIGNED_BYTE, 1: UNSIGNED_SHORT, else UNSIGNED_INT);
//   the rest:  the Draco stream,
// wrapped in a GLB with one Draco-compressed primitive (POSITION and NORMAL VEC3 FLOAT, indices F x 3) and
// imported with a 256 MiB budget. The seeds (corpus/fuzz_draco_decode/, tests/fuzz/make_draco_corpus.py) are
// draco_transcoder and draco_encoder streams (edgebreaker standard and valence, sequential) with their true
// counts, so that mutations start from streams that decode.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "fuzz_check.h"
#include "visbuf/asset/gltf_import.h"

namespace {

constexpr uint64_t kMaxMemoryBytes = uint64_t{256} << 20;
constexpr size_t kPrefix = 6;

std::string g_path;

void put32(std::vector<uint8_t>* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

// The GLB around `stream`.
std::vector<uint8_t> wrap(const uint8_t* data, size_t size) {
  const uint32_t points = uint32_t{data[0]} | uint32_t{data[1]} << 8;
  const uint32_t faces = uint32_t{data[2]} | uint32_t{data[3]} << 8;
  const int positionId = data[4] & 0x0F, normalId = data[4] >> 4;
  const int indexType = data[5] == 0 ? 5121 : data[5] == 1 ? 5123 : 5125;
  const size_t streamSize = size - kPrefix;
  const size_t binSize = (streamSize + 3) / 4 * 4 + 4;
  const std::string json =
      "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_draco_mesh_compression\"],"
      "\"extensionsRequired\":[\"KHR_draco_mesh_compression\"],"
      "\"buffers\":[{\"byteLength\":" + std::to_string(binSize) + "}],"
      "\"bufferViews\":[{\"buffer\":0,\"byteLength\":" + std::to_string(streamSize) + "}],"
      "\"accessors\":[{\"componentType\":" + std::to_string(indexType) + ",\"count\":" + std::to_string(3 * faces) +
      ",\"type\":\"SCALAR\"},{\"componentType\":5126,\"count\":" + std::to_string(points) +
      ",\"type\":\"VEC3\"},{\"componentType\":5126,\"count\":" + std::to_string(points) +
      ",\"type\":\"VEC3\"}],"
      "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":1,\"NORMAL\":2},\"indices\":0,"
      "\"extensions\":{\"KHR_draco_mesh_compression\":{\"bufferView\":0,\"attributes\":{\"POSITION\":" +
      std::to_string(positionId) + ",\"NORMAL\":" + std::to_string(normalId) + "}}}}]}],"
      "\"nodes\":[{\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}]}";
  std::string padded = json;
  while (padded.size() % 4 != 0) padded += ' ';
  std::vector<uint8_t> bin(data + kPrefix, data + size);
  bin.resize(binSize, 0);
  std::vector<uint8_t> out;
  out.insert(out.end(), {'g', 'l', 'T', 'F'});
  put32(&out, 2);
  put32(&out, static_cast<uint32_t>(12 + 8 + padded.size() + 8 + bin.size()));
  put32(&out, static_cast<uint32_t>(padded.size()));
  put32(&out, 0x4E4F534A);  // JSON
  out.insert(out.end(), padded.begin(), padded.end());
  put32(&out, static_cast<uint32_t>(bin.size()));
  put32(&out, 0x004E4942);  // BIN
  out.insert(out.end(), bin.begin(), bin.end());
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  g_path = visbuf::fuzz::privateInputPath("visbuf-fuzz-draco", "input.glb");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace visbuf;
  if (size < kPrefix) return 0;
  const std::vector<uint8_t> glb = wrap(data, size);
  visbuf::fuzz::writeInput(g_path, glb.data(), glb.size());
  GltfImportOptions options;
  options.maxMemoryBytes = kMaxMemoryBytes;
  Result<ImportedScene> scene = importGltfScene(g_path, options);
  if (!scene) {
    VISBUF_FUZZ_CHECK(!scene.error().message.empty(), "importGltfScene: error without a message");
    return 0;
  }
  for (const ImportedMesh& m : scene->meshes) {
    VISBUF_FUZZ_CHECK(m.source.indices.size() % 3 == 0, "importGltfScene: index count not a multiple of 3");
    for (uint32_t i : m.source.indices)
      VISBUF_FUZZ_CHECK(i < m.source.positions.size(), "importGltfScene: index out of range");
    for (const glm::vec3& p : m.source.positions)
      VISBUF_FUZZ_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z),
                        "importGltfScene: non-finite position from a Draco stream");
  }
  return 0;
}
