// Pack writer: serialise every section into memory, lay them out 16-byte aligned, checksum, write atomically.
#include "asset/pack_writer.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "asset/pack_animation.h"
#include "asset/pack_format.h"
#include "core/image_io.h"

namespace visbuf {

namespace {

struct Section {
  const char* name;
  uint32_t elementSize;
  uint64_t count;
  std::vector<uint8_t> bytes;
};

template <typename T>
void append(std::vector<uint8_t>& out, const T& record) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &record, sizeof(T));
}

class StringTable {
 public:
  Result<pack::StringRef> add(const std::string& s) {
    if (s.size() > std::numeric_limits<uint32_t>::max() ||
        bytes_.size() + s.size() > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded, "names and URIs exceed 4 GiB in total");
    }
    pack::StringRef ref{static_cast<uint32_t>(bytes_.size()), static_cast<uint32_t>(s.size())};
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    return ref;
  }
  std::vector<uint8_t>& bytes() { return bytes_; }

 private:
  std::vector<uint8_t> bytes_;
};

bool finite(glm::vec4 v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}
bool finite(glm::dvec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

uint64_t alignUp(uint64_t v) { return (v + pack::kAlignment - 1) & ~(pack::kAlignment - 1); }

std::string errnoText(int err) { return std::strerror(err); }

}  // namespace

Result<std::vector<uint8_t>> serializePack(const Scene& scene, PackWriteReport* report) {
  if (Status s = validateScene(scene); !s) return s.error();
  auto invalid = [](std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); };
  StringTable strings;

  // scene
  std::vector<uint8_t> sceneBytes;
  {
    const Camera& c = scene.defaultCamera;
    if (!finite(scene.anchor) || !finite(c.position) || !finite(c.target) || !finite(c.up) ||
        !std::isfinite(c.fovY) || !std::isfinite(c.nearPlane) ||
        !finite(glm::vec4(scene.lightDirection, 0.0f))) {
      return invalid("scene: non-finite anchor, camera or light direction");
    }
    pack::SceneRecord r{};
    auto name = strings.add(scene.name);
    if (!name) return name.error();
    r.name = *name;
    for (int i = 0; i < 3; ++i) {
      r.anchor[i] = scene.anchor[i];
      r.cameraPosition[i] = c.position[i];
      r.cameraTarget[i] = c.target[i];
      r.cameraUp[i] = c.up[i];
      r.lightDirection[i] = scene.lightDirection[i];
    }
    r.cameraFovY = c.fovY;
    r.cameraNear = c.nearPlane;
    append(sceneBytes, r);
  }

  // meshes, lods, vertices, indices
  std::vector<uint8_t> meshBytes, lodBytes, vertexBytes, indexBytes;
  uint64_t vertexTotal = 0, indexTotal = 0, lodTotal = 0;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& m = scene.meshes[i];
    if (m.vertices.size() > std::numeric_limits<uint32_t>::max() ||
        m.indices.size() > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded,
                       fmt::format("mesh {} '{}': more than 2^32-1 vertices or indices", i, m.name));
    }
    if (!finite(m.boundsSphere) || m.boundsSphere.w < 0.0f)
      return invalid(fmt::format("mesh {} '{}': invalid bounding sphere", i, m.name));
    for (size_t v = 0; v < m.vertices.size(); ++v) {
      const gpu::Vertex& vx = m.vertices[v];
      if (!std::isfinite(vx.px) || !std::isfinite(vx.py) || !std::isfinite(vx.pz) || !std::isfinite(vx.u) ||
          !std::isfinite(vx.v)) {
        return invalid(fmt::format("mesh {} '{}': vertex {} is not finite", i, m.name, v));
      }
    }
    pack::MeshRecord r{};
    auto name = strings.add(m.name);
    if (!name) return name.error();
    r.name = *name;
    r.firstVertex = vertexTotal;
    r.firstIndex = indexTotal;
    r.vertexCount = static_cast<uint32_t>(m.vertices.size());
    r.indexCount = static_cast<uint32_t>(m.indices.size());
    r.firstLod = static_cast<uint32_t>(lodTotal);
    r.lodCount = static_cast<uint32_t>(m.lods.size());
    for (int c = 0; c < 4; ++c) r.boundsSphere[c] = m.boundsSphere[c];
    append(meshBytes, r);
    for (const Lod& l : m.lods) {
      if (!std::isfinite(l.error) || l.error < 0.0f)
        return invalid(
            fmt::format("mesh {} '{}': LOD error {} is not a finite value >= 0", i, m.name, l.error));
      append(lodBytes, pack::LodRecord{l.firstIndex, l.indexCount, l.error, 0});
    }
    const size_t vAt = vertexBytes.size();
    vertexBytes.resize(vAt + m.vertices.size() * sizeof(gpu::Vertex));
    std::memcpy(vertexBytes.data() + vAt, m.vertices.data(), m.vertices.size() * sizeof(gpu::Vertex));
    const size_t iAt = indexBytes.size();
    indexBytes.resize(iAt + m.indices.size() * sizeof(uint32_t));
    std::memcpy(indexBytes.data() + iAt, m.indices.data(), m.indices.size() * sizeof(uint32_t));
    vertexTotal += m.vertices.size();
    indexTotal += m.indices.size();
    lodTotal += m.lods.size();
  }

  // materials
  std::vector<uint8_t> materialBytes;
  for (size_t i = 0; i < scene.materials.size(); ++i) {
    const Material& m = scene.materials[i];
    if (!finite(m.baseColor) || !std::isfinite(m.alphaCutoff))
      return invalid(fmt::format("material {} '{}': non-finite base colour or alpha cutoff", i, m.name));
    pack::MaterialRecord r{};
    auto name = strings.add(m.name);
    if (!name) return name.error();
    auto uri = strings.add(m.baseColorTexture.uri);
    if (!uri) return uri.error();
    r.name = *name;
    for (int c = 0; c < 4; ++c) r.baseColor[c] = m.baseColor[c];
    r.alphaMode = static_cast<uint32_t>(m.alphaMode);
    r.alphaCutoff = m.alphaCutoff;
    r.flags = m.doubleSided ? pack::kMaterialDoubleSided : 0u;
    r.baseColorTexture = m.baseColorTexture.texture;
    r.baseColorImage = m.baseColorTexture.image;
    r.baseColorTexCoord = m.baseColorTexture.texCoord;
    r.baseColorUri = *uri;
    append(materialBytes, r);
  }

  // objects (validateScene checked indices and finite, non-degenerate transforms)
  std::vector<uint8_t> objectBytes;
  objectBytes.reserve(scene.objects.size() * sizeof(pack::ObjectRecord));
  for (const Object& o : scene.objects) {
    pack::ObjectRecord r{};
    for (int c = 0; c < 4; ++c)
      for (int row = 0; row < 4; ++row) r.transform[c * 4 + row] = o.transform[c][row];
    r.mesh = o.mesh;
    r.material = o.material;
    append(objectBytes, r);
  }

  // optional animation sections (pack_animation.cpp); before "strings" so their names are in it
  auto animation = pack::serializeAnimationSections(scene, [&](const std::string& s) { return strings.add(s); });
  if (!animation) return animation.error();

  std::vector<Section> sections;
  sections.push_back({pack::kSceneSection, sizeof(pack::SceneRecord), 1, std::move(sceneBytes)});
  sections.push_back(
      {pack::kMeshesSection, sizeof(pack::MeshRecord), scene.meshes.size(), std::move(meshBytes)});
  sections.push_back({pack::kLodsSection, sizeof(pack::LodRecord), lodTotal, std::move(lodBytes)});
  sections.push_back({pack::kMaterialsSection, sizeof(pack::MaterialRecord), scene.materials.size(),
                      std::move(materialBytes)});
  sections.push_back(
      {pack::kObjectsSection, sizeof(pack::ObjectRecord), scene.objects.size(), std::move(objectBytes)});
  sections.push_back({pack::kVerticesSection, sizeof(gpu::Vertex), vertexTotal, std::move(vertexBytes)});
  sections.push_back({pack::kIndicesSection, sizeof(uint32_t), indexTotal, std::move(indexBytes)});
  for (pack::SectionData& a : *animation) sections.push_back({a.name, a.elementSize, a.count, std::move(a.bytes)});
  const uint64_t stringCount = strings.bytes().size();
  sections.push_back({pack::kStringsSection, 1, stringCount, std::move(strings.bytes())});

  // Layout: header, table, then each section at the next multiple of 16; the file ends 16-aligned.
  const uint64_t tableEnd = sizeof(pack::Header) + sections.size() * sizeof(pack::SectionEntry);
  std::vector<pack::SectionEntry> table(sections.size());
  uint64_t cursor = alignUp(tableEnd);
  for (size_t i = 0; i < sections.size(); ++i) {
    pack::SectionEntry& e = table[i];
    std::memset(&e, 0, sizeof(e));
    std::strncpy(e.name, sections[i].name, pack::kSectionNameSize - 1);
    e.offset = cursor;
    e.size = sections[i].bytes.size();
    e.count = sections[i].count;
    e.elementSize = sections[i].elementSize;
    e.crc32 = pack::crc32(sections[i].bytes.data(), sections[i].bytes.size());
    cursor = alignUp(cursor + e.size);
  }
  pack::Header header{};
  std::memcpy(header.magic, pack::kMagic, 4);
  header.version = pack::kVersion;
  header.headerSize = sizeof(pack::Header);
  header.sectionEntrySize = sizeof(pack::SectionEntry);
  header.sectionCount = static_cast<uint32_t>(sections.size());
  header.fileSize = cursor;
  header.headerCrc = 0;
  uint32_t crc = pack::crc32(&header, sizeof(header));
  header.headerCrc = pack::crc32(table.data(), table.size() * sizeof(pack::SectionEntry), crc);

  std::vector<uint8_t> out(cursor, 0);
  std::memcpy(out.data(), &header, sizeof(header));
  std::memcpy(out.data() + sizeof(header), table.data(), table.size() * sizeof(pack::SectionEntry));
  for (size_t i = 0; i < sections.size(); ++i) {
    if (!sections[i].bytes.empty())
      std::memcpy(out.data() + table[i].offset, sections[i].bytes.data(), sections[i].bytes.size());
  }
  if (report) {
    report->fileBytes = out.size();
    report->sections.clear();
    for (size_t i = 0; i < sections.size(); ++i)
      report->sections.push_back({sections[i].name, table[i].offset, table[i].size, table[i].count});
  }
  return out;
}

Status writePack(const Scene& scene, const std::string& path, PackWriteReport* report) {
  Result<std::vector<uint8_t>> bytes = serializePack(scene, report);
  if (!bytes) return makeError(bytes.error().code, path + ": " + bytes.error().message);

  static std::atomic<uint32_t> counter{0};
  const std::filesystem::path target(path);
  const std::filesystem::path tmp =
      target.parent_path() / fmt::format(".{}.tmp{}.{}", target.filename().string(), getpid(), counter++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    return makeError(ErrorCode::IoError, fmt::format("{}: cannot create the temporary file '{}': {}", path,
                                                     tmp.string(), errnoText(err)));
  }
  auto fail = [&](const char* what, int err) -> Status {
    ::close(fd);
    ::unlink(tmp.c_str());
    return makeError(ErrorCode::IoError, fmt::format("{}: {} failed: {} (nothing was written to {})", path,
                                                     what, errnoText(err), path));
  };
  const uint8_t* p = bytes->data();
  size_t left = bytes->size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail("write", errno);
    }
    if (n == 0) return fail("write", EIO);
    p += n;
    left -= static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("fsync", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    return makeError(ErrorCode::IoError, fmt::format("{}: close failed: {}", path, errnoText(err)));
  }
  return commitFile(tmp.string(), path);
}

}  // namespace visbuf
