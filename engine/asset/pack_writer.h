// Writes a Scene as a visbuf pack (pack_format.h, docs/pack-format.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

struct PackSectionInfo {
  std::string name;
  uint64_t offset = 0;  // bytes from the start of the file
  uint64_t size = 0;    // decoded bytes
  uint64_t count = 0;   // records
  uint64_t storedSize = 0;  // bytes in the file (== size when stored raw)
  uint32_t encoding = 0;    // pack::kSectionRaw or pack::kSectionZstd
};

// What --quantize cost, measured on the vertices the reader will decode against the scene's own.
struct PackQuantizationReport {
  bool enabled = false;
  uint64_t vertices = 0;                   // over all meshes
  double maxPositionError = 0.0;           // max |decoded - original| (Euclidean), mesh units
  double rmsPositionError = 0.0;           // RMS of the same over all vertices
  double maxRelativePositionError = 0.0;   // max of |decoded - original| / the mesh's boundsSphere radius
  double rmsRelativePositionError = 0.0;   // (meshes of radius 0 count 0)
  double maxNormalError = 0.0;             // max |decoded normal - original| (0: normals are stored unchanged)
  double maxUvError = 0.0;                 // max |decoded uv - original| (Euclidean), uv units
  int64_t bytesSaved = 0;                  // 32 bytes per vertex minus 20 per vertex and the "quantization" bytes
                                           // (decoded sizes: what the GPU pool saves, before the geometry codecs)
  std::vector<float> meshMaxPositionError;  // per mesh: added to its LOD errors in the pack (rounded up)
};

struct PackWriteReport {
  uint64_t fileBytes = 0;
  std::vector<PackSectionInfo> sections;  // in file order
  PackQuantizationReport quantization;    // enabled only when PackWriteOptions::quantize
};

struct PackWriteOptions {
  // Store "qvertices" (20 bytes: unorm16 positions over each mesh's AABB, unorm16 uvs over its uv range, normal
  // and colour unchanged) + "quantization" instead of 32-byte "vertices". Each mesh's boundsSphere is grown to
  // contain the decoded vertices and its measured max position error is added to every LOD error, so culling
  // and LOD selection stay conservative. MalformedInput when a mesh's extent overflows float.
  bool quantize = false;
  // zstd level of the section encoding (pack_section_codec.h: kMinZstdLevel..kMaxZstdLevel), 0: every section
  // raw. Each section of at least 4 KiB is compressed in 1 MiB frames and stored so when that saves 1/32 of it.
  // The decoded sections, and so the scene a reader gets, are the same at every level.
  int compressionLevel = 9;  // pack::kDefaultZstdLevel
};

// Serialises `scene` into the bytes of a pack. The scene must pass validateScene(); additionally every mesh
// must have at most 2^32-1 vertices and indices, names and URIs at most 4 GiB together, and every
// float/double finite (MalformedInput / CapacityExceeded otherwise). `report` may be null.
Result<std::vector<uint8_t>> serializePack(const Scene& scene, PackWriteReport* report = nullptr);
Result<std::vector<uint8_t>> serializePack(const Scene& scene, const PackWriteOptions& options,
                                           PackWriteReport* report = nullptr);

// Writes `scene` to `path` atomically: the bytes go to a temporary file in the same folder
// (".<name>.tmp<pid>.<n>"), which is flushed to disk (fsync) and then renamed onto `path` (commitFile).
// On any failure (serialisation, no permission, disk full, file size limit, rename) the temporary file is
// removed, `path` is left as it was (an existing pack stays intact), and an IoError names the path and the
// system's reason. While the temporary file exists, SIGINT / SIGTERM / SIGHUP (where their disposition is the
// default one) remove it and then end the process with the signal's default action. Before writing, stale
// ".<name>.tmp<pid>.<n>" files next to `path` whose process no longer exists (left by SIGKILL or a crash) are
// removed.
Status writePack(const Scene& scene, const std::string& path, PackWriteReport* report = nullptr);
Status writePack(const Scene& scene, const std::string& path, const PackWriteOptions& options,
                 PackWriteReport* report = nullptr);

}  // namespace visbuf
