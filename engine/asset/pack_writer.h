// Writes a Scene as a visbuf pack (pack_format.h, docs/pack-format.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/result.h"
#include "scene/scene.h"

namespace visbuf {

struct PackSectionInfo {
  std::string name;
  uint64_t offset = 0;  // bytes from the start of the file
  uint64_t size = 0;    // bytes
  uint64_t count = 0;   // records
};

struct PackWriteReport {
  uint64_t fileBytes = 0;
  std::vector<PackSectionInfo> sections;  // in file order
};

// Serialises `scene` into the bytes of a pack. The scene must pass validateScene(); additionally every mesh
// must have at most 2^32-1 vertices and indices, names and URIs at most 4 GiB together, and every
// float/double finite (MalformedInput / CapacityExceeded otherwise). `report` may be null.
Result<std::vector<uint8_t>> serializePack(const Scene& scene, PackWriteReport* report = nullptr);

// Writes `scene` to `path` atomically: the bytes go to a temporary file in the same folder
// (".<name>.tmp<pid>.<n>"), which is flushed to disk (fsync) and then renamed onto `path` (commitFile).
// On any failure (serialisation, no permission, disk full, file size limit, rename) the temporary file is
// removed, `path` is left as it was (an existing pack stays intact), and an IoError names the path and the
// system's reason.
Status writePack(const Scene& scene, const std::string& path, PackWriteReport* report = nullptr);

}  // namespace visbuf
