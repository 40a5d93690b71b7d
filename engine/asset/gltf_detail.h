// Internal to engine/asset: tinygltf configured once for the importer's translation units, the small
// message/range helpers they share, and the container loader. Not installed as public API.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "visbuf/core/result.h"

// tinygltf is compiled without image codecs (stb is not a dependency; texture_bake.cpp decodes images with
// OpenImageIO) and never reads external image files; loadModel keeps the encoded bytes of data: URI images in
// tinygltf::Image::image (bufferView images are read, range-checked, by collectImages).
// gltf_container.cpp defines TINYGLTF_IMPLEMENTATION before this
// include: it is the one translation unit that compiles tinygltf (do NOT link Debian's libtinygltf too).
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-variable"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <tiny_gltf.h>
#pragma GCC diagnostic pop

namespace visbuf {
struct Material;
struct ImportedImage;
struct GltfImportOptions;
}  // namespace visbuf

namespace visbuf::gltf_detail {

inline constexpr const char* kMeshoptExt = "EXT_meshopt_compression";

// True when [offset, offset + size) lies within [0, limit).
inline bool rangeFits(uint64_t offset, uint64_t size, uint64_t limit) {
  return offset <= limit && size <= limit - offset;
}
inline std::string str(uint64_t v) { return std::to_string(v); }
inline std::string str(int v) { return std::to_string(v); }
// An index held in an extension's JSON value (tinygltf leaves extensions unparsed): the value when it is a whole
// number in [0, count), else -1. Checked in double first: tinygltf's GetNumberAsInt() converts 1e30 to int,
// which is undefined.
inline int indexValue(const tinygltf::Value& v, size_t count) {
  if (!v.IsNumber()) return -1;
  const double d = v.GetNumberAsDouble();
  if (!(d >= 0.0 && d < double(count) && d == std::floor(d))) return -1;
  return static_cast<int>(d);
}
// The number as the file wrote it, for messages ("1e+30", "2.5", "7"); "(not a number)" otherwise.
inline std::string numberText(const tinygltf::Value& v) {
  if (!v.IsNumber()) return "(not a number)";
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v.GetNumberAsDouble());
  return text;
}
// " 'Name'" when the object has a name, "" otherwise: "node 3 'Foo'" / "node 3".
inline std::string named(const std::string& name) { return name.empty() ? std::string() : " '" + name + "'"; }
inline Error malformed(std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); }

// The import's memory budget (GltfImportOptions::maxMemoryBytes): a running total of what the import holds
// (the file, its buffers, decoded accessors, output streams), charged BEFORE each allocation.
class MemoryBudget {
 public:
  explicit MemoryBudget(uint64_t limit) : limit_(limit) {}
  // Adds `bytes`; CapacityExceeded naming `what` when the total would pass the limit (nothing is added then).
  Status charge(uint64_t bytes, const std::string& what);
  uint64_t limit() const { return limit_; }
  uint64_t used() const { return used_; }
  uint64_t remaining() const { return limit_ - used_; }

 private:
  uint64_t limit_;
  uint64_t used_ = 0;
};

// What loadModel() learnt about the file's external references.
struct LoadedReferences {
  // glTF image i's external file, resolved by the URI rule (uri_resolver.h); "" for embedded images.
  std::vector<std::string> imagePaths;
};

// Reads the file ourselves (only a regular file, opened without blocking: core/file_read.h; FileNotFound /
// IoError / CapacityExceeded), checks and re-packs a GLB container, refuses JSON nested deeper than 512
// levels, checks asset.version (2.x), resolves every external buffer and image uri by the URI rule
// (uri_resolver.h: anything outside the asset's folder and options.allowedUriRoots is refused before any
// file is opened), charges the file and its buffers to `budget`, neutralises EXT_meshopt_compression
// fallback buffers (tinygltf 2.7 cannot load a buffer without data), then lets tinygltf parse the JSON and
// load data-URI buffers and the external buffers approved above (through file-system callbacks that read
// nothing else). tinygltf's warnings are appended to `warnings`.
Status loadModel(const std::string& path, const GltfImportOptions& options, MemoryBudget* budget,
                 tinygltf::Model* model, LoadedReferences* references, std::vector<std::string>* warnings);

// gltf_materials.cpp (importGltfScene): materials, texture references, samplers, KHR_texture_transform.
using WarnFn = std::function<void(const std::string&)>;
// Appends every glTF material in file order (contract in gltf_import.h).
Status importMaterials(const tinygltf::Model& model, const std::string& path, const WarnFn& warn,
                       std::vector<Material>* out);
// Appends one ImportedImage per glTF image, in file order: embedded bytes (bufferView, range-checked; data:
// URI) or the resolved path of an external file (`references.imagePaths`, from loadModel; not read here).
Status collectImages(const tinygltf::Model& model, const std::string& path, const LoadedReferences& references,
                     std::vector<ImportedImage>* out);

}  // namespace visbuf::gltf_detail
