// Internal to engine/asset: tinygltf configured once for the importer's translation units, the small
// message/range helpers they share, the container loader, and the Importer class whose methods the gltf_*.cpp
// files define. Not installed as public API.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_import.h"
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

namespace visbuf::gltf_detail {

inline constexpr const char* kMeshoptExt = "EXT_meshopt_compression";
inline constexpr const char* kDracoExt = "KHR_draco_mesh_compression";

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
  // Gives back `bytes` charged earlier for a transient allocation that has been freed (the Draco decoder's
  // working set).
  void release(uint64_t bytes) { used_ -= bytes < used_ ? bytes : used_; }

 private:
  uint64_t limit_;
  uint64_t used_ = 0;
};

// What loadModel() learnt about the file's external references.
struct LoadedReferences {
  // glTF image i's external file, resolved by the URI rule (uri_resolver.h); "" for embedded images.
  std::vector<std::string> imagePaths;
  // (mesh, primitive) -> indices accessor of a KHR_draco_mesh_compression primitive whose indices accessor has
  // no bufferView: loadModel takes "indices" out of such primitives before tinygltf parses (it refuses an
  // indices accessor without a bufferView); Importer::primitiveIndices puts it back.
  std::map<std::pair<int, int>, int> dracoIndices;
};

// Reads the file ourselves (only a regular file, opened without blocking: core/file_read.h; FileNotFound /
// IoError / CapacityExceeded), checks and re-packs a GLB container, refuses JSON nested deeper than 512
// levels, checks asset.version (2.x), resolves every external buffer and image uri by the URI rule
// (uri_resolver.h: anything outside the asset's folder and options.allowedUriRoots is refused before any
// file is opened), charges the file and its buffers to `budget`, neutralises EXT_meshopt_compression
// fallback buffers (tinygltf 2.7 cannot load a buffer without data), then lets tinygltf parse the JSON and
// load data-URI buffers and the external buffers approved above (through file-system callbacks that read
// nothing else). Before the parser, auditGltfExtensions (gltf_extensions.h) refuses required extensions visbuf
// cannot honour and warns once about each used one it does not read fully. tinygltf's warnings are appended to
// `warnings`.
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

// ---------------------------------------------------------------------------------------------------------
// The importer (gltf_import.cpp: pipeline, node graph and scene walk, entry points; gltf_accessors.cpp: buffer
// views and accessors; gltf_primitives.cpp: primitive decoding and emission; gltf_scene_mesh.cpp: scene meshes
// and instances; gltf_instancing.cpp: EXT_mesh_gpu_instancing; gltf_lights.cpp: KHR_lights_punctual).

static_assert(std::endian::native == std::endian::little, "glTF data is little-endian; add byte swapping");

inline constexpr const char* kQuantizationExt = "KHR_mesh_quantization";
inline constexpr const char* kInstancingExt = "EXT_mesh_gpu_instancing";
// EXT_mesh_gpu_instancing: instances per node. Each becomes an object (importGltfScene) or a copy of the mesh
// (importGltfMesh), so the count is bounded like a viewless accessor's.
inline constexpr uint64_t kMaxInstancesPerNode = uint64_t{1} << 24;

// Accessors without a bufferView are all zeros (plus sparse substitutions): nothing in the file holds their
// elements, so their count is what a few bytes of JSON can make the import decode and the mesh build process.
// 2^20 elements (12 MiB as VEC3 floats) covers the sparse morph targets and attribute defaults that real files
// use; a mesh with more vertices stores them in a bufferView. (At 2^24 - 1 a 1 KB file held a render at 1.8 GB
// for a minute, for a mesh whose triangles nearly all collapse to one point.)
inline constexpr uint64_t kMaxViewlessAccessorCount = uint64_t{1} << 20;
// meshopt codecs compress at most ~64:1 (vertex codec, all-zero data); refuse claims far beyond that so a
// 30-byte stream cannot make us allocate gigabytes.
inline constexpr uint64_t kMaxMeshoptExpansion = 256;

// "%.3g" of a coordinate, for messages.
std::string fmtCoord(double v);
// Overflow-safe arithmetic on values read from the file.
inline bool checkedMul(uint64_t a, uint64_t b, uint64_t* out) { return !__builtin_mul_overflow(a, b, out); }
inline bool checkedAdd(uint64_t a, uint64_t b, uint64_t* out) { return !__builtin_add_overflow(a, b, out); }
bool isFinite(const glm::dmat4& m);
// The rotation matrix of a unit quaternion (x, y, z, w), glTF's order.
glm::dmat3 quaternionMatrix(double x, double y, double z, double w);
// A tangent follows the surface like a position difference (the linear part, not the normal matrix). Under a
// mirroring transform cross(normal', tangent') flips relative to the transformed bitangent, so w flips too.
glm::vec4 transformTangent(const glm::dmat3& linear, double det, const glm::vec4& t);
// Optional streams that some primitive had get their defaults for the vertices of the ones emitted after it.
void padOptionalStreams(MeshSource* m);

// What an attribute accessor may contain (glTF 2.0 core + KHR_mesh_quantization).
enum class AttributeKind {
  Position,
  Normal,
  TexCoord,
  Color,
  MorphDelta,
  Tangent,
  Joints,
  Weights,
  InstanceVec3,      // EXT_mesh_gpu_instancing TRANSLATION / SCALE
  InstanceRotation,  // EXT_mesh_gpu_instancing ROTATION
  Unchecked
};

struct Bytes {
  const uint8_t* data = nullptr;
  uint64_t size = 0;
};

// A fully validated accessor: every element read through it is in bounds.
struct AccessorPlan {
  int componentType = 0;
  bool normalized = false;
  int numComponents = 0;
  uint64_t componentSize = 0;
  uint64_t elementSize = 0;
  uint64_t count = 0;
  const uint8_t* dense = nullptr;  // first element; null: no bufferView, elements are zero
  uint64_t stride = 0;
  // Sparse substitution (sparseCount == 0: none). Index and value arrays are tightly packed.
  uint64_t sparseCount = 0;
  const uint8_t* sparseIndices = nullptr;
  uint64_t sparseIndexSize = 0;
  const uint8_t* sparseValues = nullptr;
};

using SharedVec3 = std::shared_ptr<const std::vector<glm::vec3>>;

// One primitive decoded into local space, before node transform and morph weights.
struct DecodedPrimitive {
  bool skipped = false;
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // empty: generate
  std::vector<glm::vec2> uvs;      // empty: none
  std::vector<uint32_t> colors;    // empty: none
  std::vector<glm::vec2> uvs1;     // TEXCOORD_1; empty: none
  std::vector<glm::vec4> tangents; // xyz unit, w = +-1; empty: none (or dropped as invalid)
  std::vector<glm::u16vec4> joints;  // JOINTS_0 / WEIGHTS_0, empty: none (see convertSkinAttributes)
  std::vector<glm::vec4> weights;
  std::vector<glm::u16vec4> joints1;  // JOINTS_1 / WEIGHTS_1 (influences 5-8), empty: none
  std::vector<glm::vec4> weights1;
  // Morph target deltas, one entry per target; null means the target lacks that attribute. Targets (of any
  // primitive) that name the same accessor share one decoded array (Importer::morphDeltas).
  std::vector<SharedVec3> positionDeltas;
  std::vector<SharedVec3> normalDeltas;
  std::vector<SharedVec3> tangentDeltas;  // TANGENT (xyz): kept only for animated morph targets
  std::vector<uint32_t> triangles;  // 3 local indices per triangle, counter-clockwise
};

class Importer {
 public:
  Importer(const std::string& path, const tinygltf::Model& model, const GltfImportOptions& options,
           const LoadedReferences& references, MemoryBudget* budget, std::vector<std::string>* warnings)
      : path_(path), model_(model), options_(options), references_(references), budget_(budget),
        warnings_(warnings) {}

  Result<MeshSource> run();
  Result<ImportedScene> runScene();

  uint32_t primitivesImported = 0;
  uint32_t primitivesSkipped = 0;

 private:
  void warn(const std::string& message) {
    if (warned_.insert(message).second) warnings_->push_back(message);
  }

  Status checkRequiredExtensions();
  Status checkNodeGraph();
  Status checkCoordinates(const glm::dvec3& lo, const glm::dvec3& hi, const std::string& where);
  bool isMeshoptFallbackBuffer(int buffer) const;
  Result<Bytes> viewBytes(int view, const std::string& where);
  Result<Bytes> plainViewBytes(int view, const std::string& where);
  Result<Bytes> meshoptViewBytes(int view, const std::string& where);

  // The primitive's indices accessor (-1: none), including a Draco primitive's (LoadedReferences::dracoIndices).
  int primitiveIndices(int mesh, int primitive) const;
  // KHR_draco_mesh_compression (gltf_draco.cpp): decodes the primitive's Draco stream, once, into dracoFills_
  // (the accessors it names, in their declared types), so that planAccessor reads them like any accessor.
  // Unsupported / MalformedInput / CapacityExceeded naming the problem; when the stream cannot be decoded, the
  // extension is not required and every accessor has a bufferView, warns and leaves the uncompressed data.
  Status decodeDraco(int mesh, int primitive, const std::string& where);
  Result<AccessorPlan> planAccessor(int accessor, const std::string& where);
  template <typename Fn>
  Status forEachElement(const AccessorPlan& plan, const std::string& where, Fn&& fn);
  Status readFloats(int accessor, AttributeKind kind, const std::string& where, std::vector<float>* out,
                    int* numComponents);
  Status readVec3(int accessor, AttributeKind kind, const std::string& where, bool requireFinite,
                  std::vector<glm::vec3>* out);
  Status readIndices(int accessor, const std::string& where, std::vector<uint32_t>* out);
  Status readTexCoords(int accessor, const std::string& where, std::vector<glm::vec2>* out);
  Status readTangents(int accessor, const std::string& where, std::vector<glm::vec4>* out);
  // A morph target's deltas: accessor `accessor` decoded once per import and shared by every target that names it.
  Result<SharedVec3> morphDeltas(int accessor, const std::string& where);
  // Refuses, before anything is decoded, a mesh whose decoded primitives and output would not fit the memory
  // budget (a small file whose primitives or targets share one large accessor asks for many copies of it).
  Status checkMeshFits(int mesh);
  // Adds `count` mesh instances to the import's total; CapacityExceeded naming GltfImportOptions::maxInstances
  // (and nothing added) past it.
  Status countInstances(uint64_t count, const std::string& where);

  Result<DecodedPrimitive> decodePrimitive(int mesh, int primitive);
  Status decodeSkinAttributes(const tinygltf::Primitive& prim, const std::string& where, DecodedPrimitive* out);
  Status checkSkinnedNode(int nodeIndex, const std::vector<DecodedPrimitive>& prims, const std::string& where);
  Result<const std::vector<DecodedPrimitive>*> decodedMesh(int mesh);
  // The mesh node `nodeIndex` instances, decoded, with its effective morph weights (the node's own, else
  // the mesh's defaults). mesh == nullptr when the node has no mesh.
  struct NodeMesh {
    std::string where;  // "file: node N 'name'" for messages
    const tinygltf::Mesh* mesh = nullptr;
    const std::vector<DecodedPrimitive>* prims = nullptr;
    const std::vector<double>* weights = nullptr;
  };
  Result<NodeMesh> nodeMesh(int nodeIndex);

  Result<glm::dmat4> localMatrix(int node);
  Status emitNode(int node, const glm::dmat4& world, MeshSource* out);
  Status emitPrimitive(const DecodedPrimitive& prim, const glm::dmat4& world,
                       const std::vector<double>& weights, const std::string& where, MeshSource* out);
  template <typename Visit>
  Status walkScene(Visit&& visit, std::string* sceneLabel);
  Status emitSceneNode(int node, const glm::dmat4& world, ImportedScene* scene);
  Status emitSceneMesh(int node, const glm::dmat4& world, ImportedScene* scene);
  // EXT_mesh_gpu_instancing: the world transforms of the node's mesh instances, world x T_i x R_i x S_i, or
  // just {world} when the node does not use the extension (or uses it where it cannot apply: see the .cpp).
  Result<std::vector<glm::dmat4>> meshInstances(int node, const glm::dmat4& world, bool sceneImport);
  Status emitNodeLight(int node, const glm::dmat4& world, ImportedScene* scene);
  Status emitNodeCamera(int node, const glm::dmat4& world, ImportedScene* scene);  // gltf_cameras.cpp

  // Scene import: one ImportedMesh per (glTF mesh, glTF material or -1, mirrored, morph weights, morphed,
  // one-joint). `morphed` marks a mesh that keeps its morph targets (its node's weights are animated);
  // `one-joint` a mesh whose every vertex follows joint 0 (an unskinned node whose morph weights are animated).
  using SceneMeshKey = std::tuple<int, int, bool, std::vector<double>, bool, bool>;
  std::set<int> morphAnimatedNodes_;        // nodes targeted by a weights channel of any clip
  std::set<int> movingNodes_;               // nodes whose global transform a clip animates (a TRS channel
                                            // targets them or an ancestor)
  std::map<int, int32_t> nodeSkins_;        // unskinned animated node -> its one-joint skin
  std::map<SceneMeshKey, uint32_t> sceneMeshes_;  // -> ImportedScene::meshes index, UINT32_MAX: no triangles
  std::optional<uint32_t> defaultMaterial_;
  std::vector<std::optional<std::pair<glm::dvec3, glm::dvec3>>> meshBoxes_;  // object-space box per scene mesh

  const std::string& path_;
  const tinygltf::Model& model_;
  const GltfImportOptions& options_;
  const LoadedReferences& references_;
  MemoryBudget* budget_;
  std::vector<std::string>* warnings_;
  std::set<std::string> warned_;  // de-duplicates warnings of instanced meshes
  bool meshoptRequired_ = false;
  bool instancingRequired_ = false;
  std::map<int, std::vector<uint8_t>> decodedViews_;  // meshopt scratch, by bufferView index
  std::map<int, SharedVec3> morphDeltaCache_;          // decoded morph target accessors, by accessor index
  // Accessors filled from a Draco stream: tightly packed elements of the accessor's type, and the (bufferView,
  // Draco attribute id or -1 for indices) they came from (one accessor filled from two streams is refused).
  struct DracoFill {
    std::vector<uint8_t> bytes;
    int view = -1;
    int id = -1;
  };
  std::map<int, DracoFill> dracoFills_;
  uint64_t instancesEmitted_ = 0;                       // against GltfImportOptions::maxInstances
  std::vector<std::optional<std::vector<DecodedPrimitive>>> meshCache_;
  bool warnedZeroNormals_ = false;
};

}  // namespace visbuf::gltf_detail
