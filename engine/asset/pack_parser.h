// Internal to engine/asset: the pack reader's Parser, whose methods pack_reader.cpp (section table, scene,
// materials, textures, objects, entry points) and pack_geometry.cpp (meshes, LODs and their encoded geometry
// streams) define. Not a public API: use pack_reader.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/pack_reader.h"
#include "visbuf/asset/pack_section_codec.h"
#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf::pack_detail {

// True when [offset, offset + size) lies within [0, limit).
inline bool rangeFits(uint64_t offset, uint64_t size, uint64_t limit) {
  return offset <= limit && size <= limit - offset;
}

struct SectionView {
  pack::SectionEntry entry;
  std::string name;
  // The section's decoded bytes (entry.size): in the file for a raw section, in the Parser's decoded_ for a zstd
  // one -- except "texels", whose frames readTextures decodes straight into each class (`zstd` set, `data` then
  // points at the stored bytes and is not read).
  const uint8_t* data = nullptr;
  std::shared_ptr<const pack::ZstdSection> zstd;
};

inline bool allFinite(const double* v, int n) {
  return std::all_of(v, v + n, [](double x) { return std::isfinite(x); });
}
inline bool allFinite(const float* v, int n) {
  return std::all_of(v, v + n, [](float x) { return std::isfinite(x); });
}

class Parser {
 public:
  Parser(const uint8_t* data, size_t size, const std::string& label, const PackReadOptions& options)
      : data_(data), size_(size), label_(label), options_(options) {}

  Result<Scene> run();
  uint64_t peakScratchBytes() const { return peakScratch_; }
  uint64_t largestSection() const {
    uint64_t largest = 0;
    for (const auto& [name, v] : sections_) largest = std::max(largest, v.entry.size);
    return largest;
  }

 private:
  Error fail(std::string message, ErrorCode code = ErrorCode::MalformedInput) const {
    return makeError(code, label_ + ": " + message);
  }
  Status parseTable();
  Status checkEncoding(const SectionView& v) const;  // the entry's encoding fields (step 3)
  Status decodeSections();                           // zstd sections: budget, frame checks, decode (step 4)
  template <typename T>
  T record(const SectionView& s,
           uint64_t i) const {  // caller guarantees i < count and size == count*sizeof(T)
    T r;
    std::memcpy(&r, s.data + i * sizeof(T), sizeof(T));
    return r;
  }
  Result<std::string> string(pack::StringRef ref, const std::string& where) const;
  Status readScene(Scene* scene);
  Status readMeshes(Scene* scene);
  Status readMaterials(Scene* scene);
  Status readObjects(Scene* scene);
  Status readMeshStreams(Scene* scene);
  Status readTextures(Scene* scene);
  Status readTexels(const SectionView& texels, const std::vector<uint64_t>& firstBytes, Scene* scene);
  Result<TextureRef> readTextureSlot(const pack::TextureSlotRecord& r, size_t slot, const Scene& scene,
                                     const std::string& where) const;
  // An optional section, or an empty view named `name` when the pack has none.
  SectionView optional(const char* name) const {
    auto it = sections_.find(name);
    if (it != sections_.end()) return it->second;
    SectionView empty{};
    empty.name = name;
    return empty;
  }

  // Decodes one mesh's stream of `section` (bytes [byte, byte + bytes)) into `count` records of `stride` at `out`.
  Status decodeVertices(void* out, uint64_t count, size_t stride, const SectionView& section, uint64_t byte,
                        uint64_t bytes, const std::string& where) const;
  void noteScratch(uint64_t bytes) { peakScratch_ = std::max(peakScratch_, bytes); }

  const uint8_t* data_;
  size_t size_;
  const std::string& label_;
  PackReadOptions options_;
  std::vector<std::vector<uint8_t>> decoded_;  // the decoded bytes of zstd sections (SectionView::data)
  std::map<std::string, SectionView, std::less<>> sections_;
  uint64_t peakScratch_ = 0;  // largest decode buffer besides the Scene's own storage
};

}  // namespace visbuf::pack_detail
