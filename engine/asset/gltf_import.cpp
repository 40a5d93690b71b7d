// glTF 2.0 -> MeshSource / ImportedScene importer. The contract (what is supported, which errors) is in
// gltf_import.h.
//
// Pipeline:
//   1. loadModel() (gltf_container.cpp): read the file ourselves (regular files only, never blocking;
//      FileNotFound / IoError), check and re-pack the GLB container, check asset.version, resolve every
//      external uri by the URI rule (uri_resolver.h), neutralise EXT_meshopt_compression fallback buffers
//      (tinygltf 2.7 cannot load a buffer without data), then hand the bytes to tinygltf for JSON parsing and
//      loading the data-URI buffers and the approved external ones. The file, its buffers and everything
//      decoded below are charged to the memory budget (GltfImportOptions::maxMemoryBytes) before allocation.
//   2. Importer::run(): walk the scene graph with double-precision transforms; the first time a mesh is met,
//      decode its primitives into local-space arrays (cached, so a mesh instanced by 1000 nodes is decoded
//      once); then transform, morph and append each primitive instance to the output MeshSource.
//   2'. Importer::runScene() (importGltfScene): the same walk (walkScene), but each (mesh, material,
//      mirrored, weights) group is emitted once in object space and every node becomes instances with world
//      transforms. Materials and the images they use come from gltf_materials.cpp.
//
// Safety rule: tinygltf only parses; it does not validate ranges. Every index, offset, count and stride that
// comes from the file is checked here with overflow-safe arithmetic before any byte is touched, and every
// problem becomes an Error (never an assert, exception or out-of-bounds read).

#include "visbuf/asset/gltf_import.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <limits>
#include <map>
#include <numbers>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string_view>
#include <tuple>
#include <utility>

#include "visbuf/asset/gltf_animation.h"
#include "visbuf/asset/gltf_detail.h"

namespace visbuf {
namespace {

using namespace gltf_detail;  // rangeFits, str, named, malformed, loadModel

static_assert(std::endian::native == std::endian::little, "glTF data is little-endian; add byte swapping");

constexpr const char* kQuantizationExt = "KHR_mesh_quantization";
constexpr const char* kInstancingExt = "EXT_mesh_gpu_instancing";
// EXT_mesh_gpu_instancing: instances per node. Each becomes an object (importGltfScene) or a copy of the mesh
// (importGltfMesh), so the count is bounded like a viewless accessor's.
constexpr uint64_t kMaxInstancesPerNode = uint64_t{1} << 24;

// Accessors without a bufferView are all zeros (plus sparse substitutions). Nothing in the file bounds their
// count, so cap it to keep a hostile file from requesting terabytes.
constexpr uint64_t kMaxViewlessAccessorCount = uint64_t{1} << 24;
// meshopt codecs compress at most ~64:1 (vertex codec, all-zero data); refuse claims far beyond that so a
// 30-byte stream cannot make us allocate gigabytes.
constexpr uint64_t kMaxMeshoptExpansion = 256;

// ---------------------------------------------------------------------------------------------------------
// Small helpers

std::string fmtCoord(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", v);
  return text;
}

// Overflow-safe arithmetic on values read from the file.
bool checkedMul(uint64_t a, uint64_t b, uint64_t* out) { return !__builtin_mul_overflow(a, b, out); }
bool checkedAdd(uint64_t a, uint64_t b, uint64_t* out) { return !__builtin_add_overflow(a, b, out); }

const char* componentTypeName(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case TINYGLTF_COMPONENT_TYPE_INT: return "INT";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: return "DOUBLE";
  }
  return "unknown component type";
}

// Reads one component and converts it to double. Normalized integers follow the glTF 2.0 spec
// (signed: max(c / MAX, -1); unsigned: c / MAX). The caller has validated `type` and the bounds.
double decodeComponent(const uint8_t* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
      uint8_t v;
      std::memcpy(&v, p, 1);
      return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return normalized ? v / 4294967295.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
  return 0.0;
}

// Reads an unsigned integer of 1, 2 or 4 bytes (index data).
uint32_t readUint(const uint8_t* p, uint64_t size) {
  if (size == 1) return *p;
  if (size == 2) {
    uint16_t v;
    std::memcpy(&v, p, 2);
    return v;
  }
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

uint64_t indexComponentSize(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return 4;
  }
  return 0;
}

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

// Returns "" when the accessor's type/componentType/normalized combination suits `kind`, else the reason.
std::string checkAttributeFormat(AttributeKind kind, const tinygltf::Accessor& a) {
  const int ct = a.componentType;
  const bool isFloat = ct == TINYGLTF_COMPONENT_TYPE_FLOAT;
  const bool is8or16 = ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                       ct == TINYGLTF_COMPONENT_TYPE_SHORT || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  const bool isSigned8or16 = ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_SHORT;
  const bool isUnsigned8or16 =
      ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  bool typeOk = false;
  bool componentOk = false;
  const char* expected = "";
  switch (kind) {
    case AttributeKind::Position:
      typeOk = a.type == TINYGLTF_TYPE_VEC3;
      componentOk = isFloat || is8or16;
      expected = "VEC3 of FLOAT or (normalized) BYTE/UNSIGNED_BYTE/SHORT/UNSIGNED_SHORT";
      break;
    case AttributeKind::Normal:
      typeOk = a.type == TINYGLTF_TYPE_VEC3;
      componentOk = isFloat || (isSigned8or16 && a.normalized);
      expected = "VEC3 of FLOAT or normalized BYTE/SHORT";
      break;
    case AttributeKind::TexCoord:
      typeOk = a.type == TINYGLTF_TYPE_VEC2;
      componentOk = isFloat || is8or16;
      expected = "VEC2 of FLOAT or (normalized) BYTE/UNSIGNED_BYTE/SHORT/UNSIGNED_SHORT";
      break;
    case AttributeKind::Color:
      typeOk = a.type == TINYGLTF_TYPE_VEC3 || a.type == TINYGLTF_TYPE_VEC4;
      componentOk = isFloat || (isUnsigned8or16 && a.normalized);
      expected = "VEC3/VEC4 of FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT";
      break;
    case AttributeKind::MorphDelta:
      typeOk = a.type == TINYGLTF_TYPE_VEC3;
      componentOk = isFloat || isSigned8or16;
      expected = "VEC3 of FLOAT or (normalized) BYTE/SHORT";
      break;
    case AttributeKind::Tangent:
      typeOk = a.type == TINYGLTF_TYPE_VEC4;
      componentOk = isFloat || (isSigned8or16 && a.normalized);
      expected = "VEC4 of FLOAT or normalized BYTE/SHORT";
      break;
    case AttributeKind::Joints:
      typeOk = a.type == TINYGLTF_TYPE_VEC4;
      componentOk = isUnsigned8or16 && !a.normalized;
      expected = "VEC4 of UNSIGNED_BYTE/UNSIGNED_SHORT";
      break;
    case AttributeKind::Weights:
      typeOk = a.type == TINYGLTF_TYPE_VEC4;
      componentOk = isFloat || (isUnsigned8or16 && a.normalized);
      expected = "VEC4 of FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT";
      break;
    case AttributeKind::InstanceVec3:  // the extension's table: TRANSLATION and SCALE are FLOAT only
      typeOk = a.type == TINYGLTF_TYPE_VEC3;
      componentOk = isFloat;
      expected = "VEC3 of FLOAT";
      break;
    case AttributeKind::InstanceRotation:  // FLOAT, or normalized BYTE / SHORT
      typeOk = a.type == TINYGLTF_TYPE_VEC4;
      componentOk = isFloat || (isSigned8or16 && a.normalized);
      expected = "VEC4 of FLOAT or normalized BYTE/SHORT";
      break;
    case AttributeKind::Unchecked:  // the caller checks (skins, animations: gltf_animation.cpp)
      typeOk = componentOk = true;
      break;
  }
  if (typeOk && componentOk) return {};
  return std::string("unsupported format (") + componentTypeName(ct) + (a.normalized ? " normalized" : "") +
         ", " + str(tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type))) +
         " components); expected " + expected;
}

// Packs a colour in [0,1] (clamped; NaN -> 0) as RGBA8, R in the low byte.
uint32_t packColor(const float* c, int components) {
  auto unorm8 = [](float v) -> uint32_t {
    if (!(v > 0.0f)) return 0;  // also catches NaN
    if (v >= 1.0f) return 255;
    return static_cast<uint32_t>(std::lround(v * 255.0f));
  };
  const uint32_t a = components == 4 ? unorm8(c[3]) : 255u;
  return unorm8(c[0]) | (unorm8(c[1]) << 8) | (unorm8(c[2]) << 16) | (a << 24);
}

bool isFinite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

bool allFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// Normalises tangents in place and snaps w to +-1. False (nothing usable) when any is non-finite, far from unit
// length (quantisation error is ~1e-4; exporters that write zero tangents for degenerate uvs fail here) or has
// |w| != 1.
bool validateTangents(std::vector<glm::vec4>* tangents) {
  for (glm::vec4& t : *tangents) {
    const float len = glm::length(glm::vec3(t));
    const bool unitish = std::isfinite(len) && std::abs(len - 1.0f) <= 0.1f;
    if (!unitish || !std::isfinite(t.w) || std::abs(std::abs(t.w) - 1.0f) > 0.01f) return false;
    t = glm::vec4(glm::vec3(t) / len, t.w < 0.0f ? -1.0f : 1.0f);
  }
  return true;
}

// A tangent follows the surface like a position difference (the linear part, not the normal matrix). Under a
// mirroring transform cross(normal', tangent') flips relative to the transformed bitangent, so w flips too.
glm::vec4 transformTangent(const glm::dmat3& linear, double det, const glm::vec4& t) {
  if (t.w == 0.0f) return glm::vec4(0.0f);  // "none" marker of a padded vertex
  const glm::dvec3 d = linear * glm::dvec3(t);
  const double len = glm::length(d);
  if (!(len > 0.0) || !std::isfinite(len)) return glm::vec4(0.0f);
  return glm::vec4(glm::vec3(d / len), det < 0.0 ? -t.w : t.w);
}

// The rotation matrix of a unit quaternion (x, y, z, w), glTF's order.
glm::dmat3 quaternionMatrix(double x, double y, double z, double w) {
  return glm::dmat3(1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),   // column 0
                    2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),   // column 1
                    2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y));  // column 2
}

// ---------------------------------------------------------------------------------------------------------
// Importer

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
  // Morph target deltas, one entry per target; an empty vector means the target lacks that attribute.
  std::vector<std::vector<glm::vec3>> positionDeltas;
  std::vector<std::vector<glm::vec3>> normalDeltas;
  std::vector<std::vector<glm::vec3>> tangentDeltas;  // TANGENT (xyz): kept only for animated morph targets
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

  // Scene import: one ImportedMesh per (glTF mesh, glTF material or -1, mirrored, morph weights, morphed,
  // one-joint). `morphed` marks a mesh that keeps its morph targets (its node's weights are animated);
  // `one-joint` a mesh whose every vertex follows joint 0 (an unskinned node that is animated).
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
  std::vector<std::optional<std::vector<DecodedPrimitive>>> meshCache_;
  bool warnedZeroNormals_ = false;
};

// Required extensions that change how geometry must be read are either handled or refused; the ones that only
// concern materials, textures or lights cannot change the triangles, so they are ignored.
Status Importer::checkRequiredExtensions() {
  static constexpr const char* kIgnorablePrefixes[] = {"KHR_materials_", "KHR_texture_",  "EXT_texture_",
                                                       "KHR_lights_",    "MSFT_texture_", "KHR_xmp"};
  for (const std::string& ext : model_.extensionsRequired) {
    if (ext == kMeshoptExt) {
      meshoptRequired_ = true;
      continue;
    }
    if (ext == kQuantizationExt) continue;
    if (ext == kInstancingExt) {
      instancingRequired_ = true;
      continue;
    }
    const bool ignorable = std::any_of(std::begin(kIgnorablePrefixes), std::end(kIgnorablePrefixes),
                                       [&](const char* prefix) { return ext.rfind(prefix, 0) == 0; });
    if (ignorable) continue;
    return makeError(ErrorCode::Unsupported, path_ + ": required extension '" + ext + "' is not supported");
  }
  return {};
}

bool Importer::isMeshoptFallbackBuffer(int buffer) const {
  if (buffer < 0 || static_cast<size_t>(buffer) >= model_.buffers.size()) return false;
  const auto& extensions = model_.buffers[static_cast<size_t>(buffer)].extensions;
  auto it = extensions.find(kMeshoptExt);
  if (it == extensions.end() || !it->second.IsObject()) return false;
  const tinygltf::Value& fallback = it->second.Get("fallback");
  return fallback.IsBool() && fallback.Get<bool>();
}

Result<Bytes> Importer::viewBytes(int view, const std::string& where) {
  if (view < 0 || static_cast<size_t>(view) >= model_.bufferViews.size()) {
    return malformed(where + ": bufferView " + str(view) + " does not exist");
  }
  const auto& extensions = model_.bufferViews[static_cast<size_t>(view)].extensions;
  if (extensions.count(kMeshoptExt) != 0) return meshoptViewBytes(view, where);
  return plainViewBytes(view, where);
}

// The bytes of an uncompressed bufferView, range-checked against its buffer.
Result<Bytes> Importer::plainViewBytes(int viewIndex, const std::string& where) {
  const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(viewIndex)];
  const std::string vw = where + ": bufferView " + str(viewIndex);
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model_.buffers.size()) {
    return malformed(vw + " refers to missing buffer " + str(view.buffer));
  }
  if (isMeshoptFallbackBuffer(view.buffer)) {
    return malformed(vw + " reads EXT_meshopt_compression fallback buffer " + str(view.buffer) +
                     ", which holds no data");
  }
  const std::vector<unsigned char>& data = model_.buffers[static_cast<size_t>(view.buffer)].data;
  if (!rangeFits(view.byteOffset, view.byteLength, data.size())) {
    return malformed(vw + " (byteOffset " + str(uint64_t{view.byteOffset}) + ", byteLength " +
                     str(uint64_t{view.byteLength}) + ") runs past the end of buffer " + str(view.buffer) +
                     " (" + str(uint64_t{data.size()}) + " bytes)");
  }
  return Bytes{data.data() + view.byteOffset, view.byteLength};
}

// Decodes an EXT_meshopt_compression bufferView into a scratch buffer (once; cached by view index).
Result<Bytes> Importer::meshoptViewBytes(int viewIndex, const std::string& where) {
  if (auto it = decodedViews_.find(viewIndex); it != decodedViews_.end()) {
    return Bytes{it->second.data(), it->second.size()};
  }
  const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(viewIndex)];
  const tinygltf::Value& ext = view.extensions.at(kMeshoptExt);
  const std::string vw = where + ": bufferView " + str(viewIndex) + " (" + kMeshoptExt + ")";

  // Data we understand but cannot decode (unknown mode/filter, newer codec version): use the uncompressed
  // fallback bytes when they exist and the extension is optional, else refuse as Unsupported.
  auto cannotDecode = [&](const std::string& reason) -> Result<Bytes> {
    if (meshoptRequired_ || isMeshoptFallbackBuffer(view.buffer)) {
      return makeError(ErrorCode::Unsupported, vw + ": cannot decode: " + reason);
    }
    warn(vw + ": cannot decode (" + reason + "); using the uncompressed fallback data");
    return plainViewBytes(viewIndex, where);
  };

  if (!ext.IsObject()) return malformed(vw + ": extension is not an object");
  // Unsigned integer fields; JSON numbers arrive as int or double, so validate both forms.
  auto number = [&](const char* key, bool required, uint64_t fallback, uint64_t* out) -> bool {
    if (!ext.Has(key)) {
      *out = fallback;
      return !required;
    }
    const tinygltf::Value& v = ext.Get(key);
    if (!v.IsNumber()) return false;
    const double d = v.GetNumberAsDouble();
    if (!(d >= 0.0) || d > 9007199254740992.0 || std::floor(d) != d) return false;
    *out = static_cast<uint64_t>(d);
    return true;
  };
  uint64_t buffer = 0, byteOffset = 0, byteLength = 0, byteStride = 0, count = 0;
  for (auto [key, required, dst] :
       {std::tuple{"buffer", true, &buffer}, std::tuple{"byteOffset", false, &byteOffset},
        std::tuple{"byteLength", true, &byteLength}, std::tuple{"byteStride", true, &byteStride},
        std::tuple{"count", true, &count}}) {
    if (!number(key, required, 0, dst)) return malformed(vw + ": missing or invalid '" + key + "'");
  }
  const tinygltf::Value& modeValue = ext.Get("mode");
  const std::string mode = modeValue.IsString() ? modeValue.Get<std::string>() : std::string();
  const tinygltf::Value& filterValue = ext.Get("filter");
  const std::string filter = filterValue.IsString() ? filterValue.Get<std::string>() : "NONE";

  // Mode / filter constraints from the extension spec (they are also the decoder's preconditions, which it
  // asserts on, so they must be checked before calling it).
  uint8_t expectedHeader = 0;
  if (mode == "ATTRIBUTES") {
    expectedHeader = 0xA0;
    if (byteStride == 0 || byteStride > 256 || byteStride % 4 != 0) {
      return malformed(vw + ": ATTRIBUTES byteStride " + str(byteStride) +
                       " must be a multiple of 4 in [4, 256]");
    }
  } else if (mode == "TRIANGLES" || mode == "INDICES") {
    expectedHeader = mode == "TRIANGLES" ? 0xE0 : 0xD0;
    if (byteStride != 2 && byteStride != 4) return malformed(vw + ": " + mode + " byteStride must be 2 or 4");
    if (mode == "TRIANGLES" && count % 3 != 0)
      return malformed(vw + ": TRIANGLES count must be a multiple of 3");
  } else {
    return cannotDecode("unknown mode '" + mode + "'");
  }
  if (filter != "NONE") {
    if (mode != "ATTRIBUTES") return malformed(vw + ": filter '" + filter + "' requires mode ATTRIBUTES");
    if (filter == "OCTAHEDRAL") {
      if (byteStride != 4 && byteStride != 8)
        return malformed(vw + ": OCTAHEDRAL filter needs byteStride 4 or 8");
    } else if (filter == "QUATERNION") {
      if (byteStride != 8) return malformed(vw + ": QUATERNION filter needs byteStride 8");
    } else if (filter != "EXPONENTIAL") {
      return cannotDecode("unknown filter '" + filter + "'");
    }
  }

  // Source range and decoded size.
  if (buffer >= model_.buffers.size()) return malformed(vw + ": refers to missing buffer " + str(buffer));
  if (isMeshoptFallbackBuffer(static_cast<int>(buffer))) {
    return malformed(vw + ": compressed data lives in a fallback buffer");
  }
  const std::vector<unsigned char>& source = model_.buffers[buffer].data;
  if (!rangeFits(byteOffset, byteLength, source.size())) {
    return malformed(vw + ": compressed range (byteOffset " + str(byteOffset) + ", byteLength " +
                     str(byteLength) + ") runs past the end of buffer " + str(buffer) + " (" +
                     str(uint64_t{source.size()}) + " bytes)");
  }
  uint64_t decodedSize = 0;
  if (!checkedMul(count, byteStride, &decodedSize) || decodedSize > view.byteLength) {
    return malformed(vw + ": count " + str(count) + " x byteStride " + str(byteStride) +
                     " exceeds the bufferView byteLength " + str(uint64_t{view.byteLength}));
  }
  if (decodedSize / kMaxMeshoptExpansion > byteLength + 1024) {
    return malformed(vw + ": decoded size " + str(decodedSize) + " is implausibly large for " +
                     str(byteLength) + " compressed bytes");
  }

  if (Status s = budget_->charge(decodedSize, vw); !s) return s.error();
  std::vector<uint8_t> decoded(decodedSize);
  if (count > 0) {
    const uint8_t* src = source.data() + byteOffset;
    if (byteLength == 0 || (src[0] & 0xF0) != expectedHeader) {
      return malformed(vw + ": data is not a meshopt " + mode + " stream");
    }
    // meshoptimizer 0.18 decodes vertex codec version 0 and index codec versions 0 and 1; newer streams are
    // valid data that this build cannot read.
    const int version = src[0] & 0x0F;
    const int maxVersion = mode == "ATTRIBUTES" ? 0 : 1;
    if (version > maxVersion) return cannotDecode(mode + " codec version " + str(version));
    int rc = 0;
    if (mode == "ATTRIBUTES") {
      rc = meshopt_decodeVertexBuffer(decoded.data(), count, byteStride, src, byteLength);
    } else if (mode == "TRIANGLES") {
      rc = meshopt_decodeIndexBuffer(decoded.data(), count, byteStride, src, byteLength);
    } else {
      rc = meshopt_decodeIndexSequence(decoded.data(), count, byteStride, src, byteLength);
    }
    // -1: unsupported header/version (checked above, so not expected); -2/-3: truncated or corrupt data.
    if (rc == -1) return cannotDecode(mode + " stream header not supported by meshoptimizer 0.18");
    if (rc != 0) return malformed(vw + ": meshopt decoder rejected the data (error " + str(rc) + ")");
    if (filter == "OCTAHEDRAL") meshopt_decodeFilterOct(decoded.data(), count, byteStride);
    if (filter == "QUATERNION") meshopt_decodeFilterQuat(decoded.data(), count, byteStride);
    if (filter == "EXPONENTIAL") meshopt_decodeFilterExp(decoded.data(), count, byteStride);
  }
  auto& stored = decodedViews_[viewIndex] = std::move(decoded);
  return Bytes{stored.data(), stored.size()};
}

// Validates an accessor completely (type, bufferView, dense range, sparse ranges) without reading values.
Result<AccessorPlan> Importer::planAccessor(int index, const std::string& where) {
  if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size()) {
    return malformed(where + ": accessor does not exist");
  }
  const tinygltf::Accessor& acc = model_.accessors[static_cast<size_t>(index)];
  AccessorPlan plan;
  plan.componentType = acc.componentType;
  plan.normalized = acc.normalized;
  plan.numComponents = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
  const int componentSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
  if (plan.numComponents <= 0 || componentSize <= 0)
    return malformed(where + ": invalid type or componentType");
  plan.componentSize = static_cast<uint64_t>(componentSize);
  plan.elementSize = plan.componentSize * static_cast<uint64_t>(plan.numComponents);
  plan.count = acc.count;

  if (acc.bufferView >= 0) {
    auto bytes = viewBytes(acc.bufferView, where);
    if (!bytes) return bytes.error();
    const uint64_t viewStride = model_.bufferViews[static_cast<size_t>(acc.bufferView)].byteStride;
    plan.stride = viewStride != 0 ? viewStride : plan.elementSize;
    if (plan.stride < plan.elementSize) {
      return malformed(where + ": byteStride " + str(plan.stride) + " is smaller than the element size " +
                       str(plan.elementSize));
    }
    if (plan.count > 0) {
      uint64_t span = 0;  // bytes from the first element's start to the last element's end
      if (!checkedMul(plan.count - 1, plan.stride, &span) || !checkedAdd(span, plan.elementSize, &span) ||
          !rangeFits(acc.byteOffset, span, bytes->size)) {
        return malformed(where + ": byteOffset " + str(uint64_t{acc.byteOffset}) + " + count " +
                         str(plan.count) + " x stride " + str(plan.stride) +
                         " runs past the end of bufferView " + str(acc.bufferView) + " (" + str(bytes->size) +
                         " bytes)");
      }
      plan.dense = bytes->data + acc.byteOffset;
    }
  } else if (plan.count > kMaxViewlessAccessorCount) {
    return malformed(where + ": count " + str(plan.count) + " without a bufferView exceeds the limit " +
                     str(kMaxViewlessAccessorCount));
  }

  if (acc.sparse.isSparse) {
    const auto& sparse = acc.sparse;
    if (sparse.count <= 0 || static_cast<uint64_t>(sparse.count) > plan.count) {
      return malformed(where + ": sparse count " + str(sparse.count) + " is not in [1, " + str(plan.count) +
                       "]");
    }
    if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0) {
      return malformed(where + ": negative sparse byteOffset");
    }
    plan.sparseCount = static_cast<uint64_t>(sparse.count);
    plan.sparseIndexSize = indexComponentSize(sparse.indices.componentType);
    if (plan.sparseIndexSize == 0) {
      return malformed(where + ": sparse indices must be UNSIGNED_BYTE/SHORT/INT, not " +
                       componentTypeName(sparse.indices.componentType));
    }
    auto indexBytes = viewBytes(sparse.indices.bufferView, where + " sparse indices");
    if (!indexBytes) return indexBytes.error();
    auto valueBytes = viewBytes(sparse.values.bufferView, where + " sparse values");
    if (!valueBytes) return valueBytes.error();
    const uint64_t indexOffset = static_cast<uint64_t>(sparse.indices.byteOffset);
    const uint64_t valueOffset = static_cast<uint64_t>(sparse.values.byteOffset);
    // Both products are bounded by count (<= SIZE_MAX / 16-ish from the JSON int) times <= 16: no overflow.
    if (!rangeFits(indexOffset, plan.sparseCount * plan.sparseIndexSize, indexBytes->size)) {
      return malformed(where + ": sparse indices (byteOffset " + str(indexOffset) + ", count " +
                       str(plan.sparseCount) + ") run past the end of bufferView " +
                       str(sparse.indices.bufferView) + " (" + str(indexBytes->size) + " bytes)");
    }
    if (!rangeFits(valueOffset, plan.sparseCount * plan.elementSize, valueBytes->size)) {
      return malformed(where + ": sparse values (byteOffset " + str(valueOffset) + ", count " +
                       str(plan.sparseCount) + ") run past the end of bufferView " +
                       str(sparse.values.bufferView) + " (" + str(valueBytes->size) + " bytes)");
    }
    plan.sparseIndices = indexBytes->data + indexOffset;
    plan.sparseValues = valueBytes->data + valueOffset;
  }
  return plan;
}

// Calls fn(elementIndex, elementBytes) for every element (elementBytes == nullptr: the element is zero),
// dense elements first, then the sparse substitutions, so later calls overwrite earlier ones.
template <typename Fn>
Status Importer::forEachElement(const AccessorPlan& plan, const std::string& where, Fn&& fn) {
  for (uint64_t i = 0; i < plan.count; ++i) fn(i, plan.dense ? plan.dense + i * plan.stride : nullptr);
  for (uint64_t k = 0; k < plan.sparseCount; ++k) {
    const uint32_t target = readUint(plan.sparseIndices + k * plan.sparseIndexSize, plan.sparseIndexSize);
    if (target >= plan.count) {
      return malformed(where + ": sparse index " + str(uint64_t{target}) + " (entry " + str(k) +
                       ") is not below the accessor count " + str(plan.count));
    }
    fn(target, plan.sparseValues + k * plan.elementSize);
  }
  return {};
}

Status Importer::readFloats(int accessor, AttributeKind kind, const std::string& where,
                            std::vector<float>* out, int* numComponents) {
  auto plan = planAccessor(accessor, where);
  if (!plan) return plan.error();
  const std::string why = checkAttributeFormat(kind, model_.accessors[static_cast<size_t>(accessor)]);
  if (!why.empty()) return malformed(where + ": " + why);
  const int n = plan->numComponents;
  *numComponents = n;
  if (Status s = budget_->charge(plan->count * static_cast<uint64_t>(n) * sizeof(float), where); !s) return s;
  out->assign(plan->count * static_cast<uint64_t>(n), 0.0f);
  const AccessorPlan& p = *plan;
  return forEachElement(p, where, [&](uint64_t i, const uint8_t* element) {
    float* dst = out->data() + i * static_cast<uint64_t>(n);
    for (int c = 0; c < n; ++c) {
      dst[c] = element
                   ? static_cast<float>(decodeComponent(element + static_cast<uint64_t>(c) * p.componentSize,
                                                        p.componentType, p.normalized))
                   : 0.0f;
    }
  });
}

Status Importer::readVec3(int accessor, AttributeKind kind, const std::string& where, bool requireFinite,
                          std::vector<glm::vec3>* out) {
  std::vector<float> flat;
  int n = 0;
  if (Status s = readFloats(accessor, kind, where, &flat, &n); !s) return s;
  out->resize(flat.size() / 3);
  for (size_t i = 0; i < out->size(); ++i) {
    const glm::vec3 v(flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]);
    if (requireFinite && !(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z))) {
      return malformed(where + ": non-finite value (NaN or Inf) in element " + str(uint64_t{i}));
    }
    (*out)[i] = v;
  }
  return {};
}

Status Importer::readIndices(int accessor, const std::string& where, std::vector<uint32_t>* out) {
  auto plan = planAccessor(accessor, where);
  if (!plan) return plan.error();
  const uint64_t size = indexComponentSize(plan->componentType);
  if (plan->numComponents != 1 || size == 0) {
    return malformed(where + ": indices must be SCALAR UNSIGNED_BYTE/SHORT/INT, not " +
                     componentTypeName(plan->componentType) + " x" + str(plan->numComponents));
  }
  if (Status s = budget_->charge(plan->count * sizeof(uint32_t), where); !s) return s;
  out->assign(plan->count, 0);
  return forEachElement(*plan, where, [&](uint64_t i, const uint8_t* element) {
    (*out)[i] = element ? readUint(element, size) : 0;
  });
}

Status Importer::readTexCoords(int accessor, const std::string& where, std::vector<glm::vec2>* out) {
  std::vector<float> flat;
  int n = 0;
  if (Status s = readFloats(accessor, AttributeKind::TexCoord, where, &flat, &n); !s) return s;
  out->resize(flat.size() / 2);
  bool replaced = false;
  for (size_t i = 0; i < out->size(); ++i) {
    glm::vec2 uv(flat[2 * i], flat[2 * i + 1]);
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {  // uvs cannot corrupt geometry: repair, don't fail
      uv = glm::vec2(0.0f);
      replaced = true;
    }
    (*out)[i] = uv;
  }
  if (replaced) warn(where + ": non-finite texture coordinates replaced by (0, 0)");
  return {};
}

Status Importer::readTangents(int accessor, const std::string& where, std::vector<glm::vec4>* out) {
  std::vector<float> flat;
  int n = 0;
  if (Status s = readFloats(accessor, AttributeKind::Tangent, where, &flat, &n); !s) return s;
  out->resize(flat.size() / 4);
  for (size_t i = 0; i < out->size(); ++i)
    (*out)[i] = glm::vec4(flat[4 * i], flat[4 * i + 1], flat[4 * i + 2], flat[4 * i + 3]);
  return {};
}

Result<DecodedPrimitive> Importer::decodePrimitive(int meshIndex, int primIndex) {
  const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(meshIndex)];
  const tinygltf::Primitive& prim = mesh.primitives[static_cast<size_t>(primIndex)];
  const std::string where =
      path_ + ": mesh " + str(meshIndex) + named(mesh.name) + " primitive " + str(primIndex);
  auto accessorWhere = [&](int accessor, const std::string& semantic) {
    return where + " accessor " + str(accessor) + " (" + semantic + ")";
  };
  DecodedPrimitive out;

  const int mode = prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    static constexpr const char* kModeNames[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP"};
    const std::string name = (mode >= 0 && mode <= 3) ? kModeNames[mode] : "unknown mode " + str(mode);
    warn(where + ": " + name + " primitive skipped (only triangles are imported)");
    out.skipped = true;
    return out;
  }
  auto positionIt = prim.attributes.find("POSITION");
  if (positionIt == prim.attributes.end()) {
    warn(where + ": no POSITION attribute; primitive skipped");
    out.skipped = true;
    return out;
  }

  // Vertex attributes. All must have POSITION's count.
  if (Status s = readVec3(positionIt->second, AttributeKind::Position,
                          accessorWhere(positionIt->second, "POSITION"), true, &out.positions);
      !s) {
    return s.error();
  }
  const uint64_t vertexCount = out.positions.size();
  auto checkCount = [&](uint64_t count, int accessor, const std::string& semantic) -> Status {
    if (count == vertexCount) return {};
    return malformed(accessorWhere(accessor, semantic) + ": count " + str(count) +
                     " differs from POSITION count " + str(vertexCount));
  };
  if (auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "NORMAL");
    if (Status s = readVec3(it->second, AttributeKind::Normal, w, true, &out.normals); !s) return s.error();
    if (Status s = checkCount(out.normals.size(), it->second, "NORMAL"); !s) return s.error();
  }
  for (auto [semantic, dst] : {std::pair{"TEXCOORD_0", &out.uvs}, std::pair{"TEXCOORD_1", &out.uvs1}}) {
    auto it = prim.attributes.find(semantic);
    if (it == prim.attributes.end()) continue;
    if (Status s = readTexCoords(it->second, accessorWhere(it->second, semantic), dst); !s) return s.error();
    if (Status s = checkCount(dst->size(), it->second, semantic); !s) return s.error();
  }
  if (auto it = prim.attributes.find("TANGENT"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "TANGENT");
    if (Status s = readTangents(it->second, w, &out.tangents); !s) return s.error();
    if (Status s = checkCount(out.tangents.size(), it->second, "TANGENT"); !s) return s.error();
    if (!validateTangents(&out.tangents)) {
      warn(w + ": tangents are not finite unit vectors with w = +-1; dropped (the renderer derives them)");
      out.tangents.clear();
    }
  }
  if (auto it = prim.attributes.find("COLOR_0"); it != prim.attributes.end()) {
    const std::string w = accessorWhere(it->second, "COLOR_0");
    std::vector<float> flat;
    int n = 0;
    if (Status s = readFloats(it->second, AttributeKind::Color, w, &flat, &n); !s) return s.error();
    if (Status s = checkCount(flat.size() / static_cast<uint64_t>(n), it->second, "COLOR_0"); !s)
      return s.error();
    out.colors.resize(vertexCount);
    for (uint64_t i = 0; i < vertexCount; ++i)
      out.colors[i] = packColor(&flat[i * static_cast<uint64_t>(n)], n);
  }
  if (Status s = decodeSkinAttributes(prim, where, &out); !s) return s.error();

  // Morph targets (only POSITION and NORMAL matter for a baked mesh; TANGENT too for an animated one).
  for (size_t t = 0; t < prim.targets.size(); ++t) {
    std::vector<glm::vec3> positionDelta;
    std::vector<glm::vec3> normalDelta;
    std::vector<glm::vec3> tangentDelta;
    const std::string target = " target " + str(uint64_t{t});
    for (auto [semantic, dst] : {std::pair{"POSITION", &positionDelta}, std::pair{"NORMAL", &normalDelta},
                                 std::pair{"TANGENT", &tangentDelta}}) {
      auto it = prim.targets[t].find(semantic);
      if (it == prim.targets[t].end()) continue;
      const std::string w = where + target + " accessor " + str(it->second) + " (" + semantic + ")";
      if (Status s = readVec3(it->second, AttributeKind::MorphDelta, w, true, dst); !s) return s.error();
      if (dst->size() != vertexCount) {
        return malformed(w + ": count " + str(uint64_t{dst->size()}) + " differs from POSITION count " +
                         str(vertexCount));
      }
    }
    out.positionDeltas.push_back(std::move(positionDelta));
    out.normalDeltas.push_back(std::move(normalDelta));
    out.tangentDeltas.push_back(std::move(tangentDelta));
  }

  // Indices: explicit or sequential; then convert the topology to a triangle list.
  std::vector<uint32_t> indices;
  if (prim.indices >= 0) {
    const std::string w = accessorWhere(prim.indices, "indices");
    if (Status s = readIndices(prim.indices, w, &indices); !s) return s.error();
    for (size_t i = 0; i < indices.size(); ++i) {
      if (indices[i] >= vertexCount) {
        return malformed(w + ": index value " + str(uint64_t{indices[i]}) + " at position " +
                         str(uint64_t{i}) + " is not below the vertex count " + str(vertexCount));
      }
    }
  } else {
    if (vertexCount > std::numeric_limits<uint32_t>::max()) {
      return makeError(ErrorCode::CapacityExceeded, where + ": more than 2^32-1 vertices");
    }
    if (Status s = budget_->charge(vertexCount * sizeof(uint32_t), where); !s) return s.error();
    indices.resize(vertexCount);
    for (uint64_t i = 0; i < vertexCount; ++i) indices[i] = static_cast<uint32_t>(i);
  }
  const size_t n = indices.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3 != 0)
      warn(where + ": index count " + str(uint64_t{n}) + " is not a multiple of 3; extra ignored");
    out.triangles.assign(indices.begin(), indices.begin() + static_cast<std::ptrdiff_t>(n - n % 3));
  } else {
    // Strips and fans; triangles that repeat an index are stitching artefacts (strip restarts), so drop them.
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
      if (a == b || b == c || a == c) return;
      out.triangles.insert(out.triangles.end(), {a, b, c});
    };
    for (size_t i = 0; i + 2 < n; ++i) {
      if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // Spec: odd triangles swap their first two vertices to keep a consistent winding.
        if (i % 2 == 0) {
          add(indices[i], indices[i + 1], indices[i + 2]);
        } else {
          add(indices[i + 1], indices[i], indices[i + 2]);
        }
      } else {
        add(indices[i + 1], indices[i + 2], indices[0]);  // spec: fan triangle i = (p[i+1], p[i+2], p[0])
      }
    }
  }
  if (out.triangles.empty()) {
    warn(where + ": no triangles; primitive skipped");
    out.skipped = true;
  }
  return out;
}

// JOINTS_0 + WEIGHTS_0 (both or neither), and JOINTS_1 + WEIGHTS_1 (both or neither, only beside set 0): up to 8
// influences, normalised together. JOINTS_2+ are ignored with a warning (the skinning pass takes 8).
Status Importer::decodeSkinAttributes(const tinygltf::Primitive& prim, const std::string& where,
                                      DecodedPrimitive* out) {
  auto joints = prim.attributes.find("JOINTS_0");
  auto weights = prim.attributes.find("WEIGHTS_0");
  if (joints == prim.attributes.end() && weights == prim.attributes.end()) return {};
  if (joints == prim.attributes.end() || weights == prim.attributes.end()) {
    warn(where + ": JOINTS_0 and WEIGHTS_0 must come together; skinning attributes ignored");
    return {};
  }
  auto joints1 = prim.attributes.find("JOINTS_1");
  auto weights1 = prim.attributes.find("WEIGHTS_1");
  const bool second = joints1 != prim.attributes.end() && weights1 != prim.attributes.end();
  if (!second && (joints1 != prim.attributes.end() || weights1 != prim.attributes.end()))
    return malformed(where + ": JOINTS_1 and WEIGHTS_1 must come together");
  if (prim.attributes.count("JOINTS_2") != 0 || prim.attributes.count("WEIGHTS_2") != 0)
    warn(where + ": JOINTS_2+ / WEIGHTS_2+ ignored (at most 8 influences per vertex); the weights of sets 0 and 1 "
                 "are renormalised without them");
  const int influences = second ? 8 : 4;
  const size_t vertices = out->positions.size();
  // Joint and weight values, `influences` per vertex: set 0's four, then set 1's.
  std::vector<float> flat[2];
  flat[0].resize(vertices * static_cast<size_t>(influences));
  flat[1].resize(vertices * static_cast<size_t>(influences));
  using It = std::map<std::string, int>::const_iterator;
  const std::tuple<It, AttributeKind, int, int> sets[] = {
      {joints, AttributeKind::Joints, 0, 0}, {weights, AttributeKind::Weights, 1, 0},
      {joints1, AttributeKind::Joints, 0, 1}, {weights1, AttributeKind::Weights, 1, 1}};
  for (const auto& [it, kind, k, set] : sets) {
    if (set == 1 && !second) continue;
    const std::string w = where + " accessor " + str(it->second) + " (" + it->first + ")";
    std::vector<float> values;
    int n = 0;
    if (Status s = readFloats(it->second, kind, w, &values, &n); !s) return s;
    if (values.size() != vertices * 4) {
      return malformed(w + ": count " + str(uint64_t{values.size() / 4}) + " differs from POSITION count " +
                       str(uint64_t{vertices}));
    }
    for (size_t v = 0; v < vertices; ++v)
      for (size_t c = 0; c < 4; ++c)
        flat[k][v * static_cast<size_t>(influences) + static_cast<size_t>(set) * 4 + c] = values[v * 4 + c];
  }
  const std::string w = where + " accessor " + str(weights->second) + " (WEIGHTS_0" +
                        (second ? " + WEIGHTS_1 accessor " + str(weights1->second) : std::string()) + ")";
  SkinStreams streams;
  if (Status s = convertSkinAttributes(flat[0], flat[1], influences, w, [this](const std::string& m) { warn(m); },
                                       &streams);
      !s)
    return s;
  out->joints = std::move(streams.joints);
  out->weights = std::move(streams.weights);
  out->joints1 = std::move(streams.joints1);
  out->weights1 = std::move(streams.weights1);
  return {};
}

Result<const std::vector<DecodedPrimitive>*> Importer::decodedMesh(int mesh) {
  auto& slot = meshCache_[static_cast<size_t>(mesh)];
  if (!slot) {
    std::vector<DecodedPrimitive> prims;
    const size_t count = model_.meshes[static_cast<size_t>(mesh)].primitives.size();
    for (size_t p = 0; p < count; ++p) {
      auto decoded = decodePrimitive(mesh, static_cast<int>(p));
      if (!decoded) return decoded.error();
      prims.push_back(std::move(decoded).value());
    }
    slot = std::move(prims);
  }
  return &*slot;
}

// The node's local transform: `matrix` (column-major) or T * R * S. Non-finite values are an error.
Result<glm::dmat4> Importer::localMatrix(int nodeIndex) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  const std::string where = path_ + ": node " + str(nodeIndex) + named(node.name);
  if (!allFinite(node.matrix) || !allFinite(node.translation) || !allFinite(node.rotation) ||
      !allFinite(node.scale)) {
    return malformed(where + ": non-finite transform");
  }
  glm::dmat4 m(1.0);
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16) return malformed(where + ": matrix must have 16 elements");
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<size_t>(c * 4 + r)];
    return m;
  }
  if (!node.translation.empty() && node.translation.size() != 3) {
    return malformed(where + ": translation must have 3 elements");
  }
  if (!node.rotation.empty() && node.rotation.size() != 4)
    return malformed(where + ": rotation must have 4 elements");
  if (!node.scale.empty() && node.scale.size() != 3) return malformed(where + ": scale must have 3 elements");
  glm::dmat3 rs(1.0);
  if (!node.rotation.empty()) {
    // glTF quaternions are (x, y, z, w). Normalise defensively: exporters write slightly non-unit values.
    double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
    const double len = std::sqrt(x * x + y * y + z * z + w * w);
    if (!(len > 0.0) || !std::isfinite(len)) {
      warn(where + ": zero-length or out-of-range rotation quaternion treated as identity");
    } else {
      rs = quaternionMatrix(x / len, y / len, z / len, w / len);
    }
  }
  if (!node.scale.empty()) {
    for (int c = 0; c < 3; ++c) rs[c] *= node.scale[static_cast<size_t>(c)];
  }
  m = glm::dmat4(rs);
  if (!node.translation.empty())
    m[3] = glm::dvec4(node.translation[0], node.translation[1], node.translation[2], 1.0);
  return m;
}

// Appends one primitive instance: morph, transform, winding fix-up, normals.
Status Importer::emitPrimitive(const DecodedPrimitive& prim, const glm::dmat4& world,
                               const std::vector<double>& weights, const std::string& where,
                               MeshSource* out) {
  const size_t base = out->positions.size();
  const size_t count = prim.positions.size();
  if (count > std::numeric_limits<uint32_t>::max() - base) {
    return makeError(ErrorCode::CapacityExceeded, where + ": the scene has more than 2^32-1 vertices");
  }
  const size_t targets = std::min(weights.size(), prim.positionDeltas.size());
  if (weights.size() != prim.positionDeltas.size() && !weights.empty()) {
    warn(where + ": " + str(uint64_t{weights.size()}) + " morph weights for " +
         str(uint64_t{prim.positionDeltas.size()}) + " targets; using the first " + str(uint64_t{targets}));
  }

  // Normals go through the cofactor matrix (= det * inverse-transpose), which also exists for singular
  // matrices; multiplying by sign(det) makes it point like the inverse-transpose.
  const glm::dmat3 linear(world);
  const double det = glm::determinant(linear);
  const glm::dmat3 normalMatrix =
      glm::dmat3(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]),
                 glm::cross(linear[0], linear[1])) *
      (det < 0.0 ? -1.0 : 1.0);
  const bool flip = det < 0.0;

  // What this primitive instance adds to the output (positions, normals, indices, the optional streams).
  uint64_t perVertex = 2 * sizeof(glm::vec3);
  if (!prim.uvs.empty()) perVertex += sizeof(glm::vec2);
  if (!prim.uvs1.empty()) perVertex += sizeof(glm::vec2);
  if (!prim.colors.empty()) perVertex += sizeof(uint32_t);
  if (!prim.tangents.empty()) perVertex += sizeof(glm::vec4);
  if (!prim.joints.empty()) perVertex += sizeof(glm::u16vec4) + sizeof(glm::vec4);
  if (!prim.joints1.empty()) perVertex += sizeof(glm::u16vec4) + sizeof(glm::vec4);
  perVertex += (prim.positionDeltas.size() + prim.normalDeltas.size()) * sizeof(glm::vec3);
  if (Status s = budget_->charge(count * perVertex + prim.triangles.size() * sizeof(uint32_t), where); !s) return s;

  out->positions.resize(base + count);
  out->normals.resize(base + count);
  std::vector<uint8_t> needsNormal(count, prim.normals.empty() ? 1 : 0);
  size_t zeroNormals = 0;
  for (size_t v = 0; v < count; ++v) {
    glm::dvec3 p(prim.positions[v]);
    for (size_t t = 0; t < targets; ++t) {
      if (!prim.positionDeltas[t].empty()) p += weights[t] * glm::dvec3(prim.positionDeltas[t][v]);
    }
    const glm::dvec3 wp = glm::dvec3(world * glm::dvec4(p, 1.0));
    const glm::vec3 fp(wp);
    if (!std::isfinite(fp.x) || !std::isfinite(fp.y) || !std::isfinite(fp.z)) {
      return malformed(where + ": vertex " + str(uint64_t{v}) + " is non-finite after the node transform");
    }
    if (!(std::abs(wp.x) <= kMaxImportCoordinate && std::abs(wp.y) <= kMaxImportCoordinate &&
          std::abs(wp.z) <= kMaxImportCoordinate)) {
      return malformed(where + ": vertex " + str(uint64_t{v}) + " at (" + fmtCoord(wp.x) + ", " + fmtCoord(wp.y) +
                       ", " + fmtCoord(wp.z) + ") is too far from the origin (|coordinate| > " +
                       fmtCoord(kMaxImportCoordinate) + "): its bounds would overflow");
    }
    out->positions[base + v] = fp;
    if (!prim.normals.empty()) {
      glm::dvec3 n(prim.normals[v]);
      for (size_t t = 0; t < targets; ++t) {
        if (!prim.normalDeltas[t].empty()) n += weights[t] * glm::dvec3(prim.normalDeltas[t][v]);
      }
      n = normalMatrix * n;
      const double len = glm::length(n);
      if (len > 0.0 && std::isfinite(len)) {
        out->normals[base + v] = glm::vec3(n / len);
      } else {
        needsNormal[v] = 1;
        ++zeroNormals;
      }
    }
  }

  const size_t firstIndex = out->indices.size();
  out->indices.resize(firstIndex + prim.triangles.size());
  for (size_t i = 0; i < prim.triangles.size(); i += 3) {
    const uint32_t b = static_cast<uint32_t>(base);
    out->indices[firstIndex + i] = b + prim.triangles[i];
    out->indices[firstIndex + i + 1] = b + prim.triangles[flip ? i + 2 : i + 1];
    out->indices[firstIndex + i + 2] = b + prim.triangles[flip ? i + 1 : i + 2];
  }

  // Missing (or unusable) normals: area-weighted vertex normals of this primitive instance, from the final
  // positions and winding. The cross product's length is twice the triangle area, hence the weighting.
  const bool anyNeeded = prim.normals.empty() || zeroNormals > 0;
  if (anyNeeded && options_.generateNormalsIfMissing) {
    std::vector<glm::dvec3> accum(count, glm::dvec3(0.0));
    for (size_t i = firstIndex; i < out->indices.size(); i += 3) {
      const uint32_t a = out->indices[i], b = out->indices[i + 1], c = out->indices[i + 2];
      const glm::dvec3 pa(out->positions[a]), pb(out->positions[b]), pc(out->positions[c]);
      const glm::dvec3 faceNormal = glm::cross(pb - pa, pc - pa);
      accum[a - base] += faceNormal;
      accum[b - base] += faceNormal;
      accum[c - base] += faceNormal;
    }
    for (size_t v = 0; v < count; ++v) {
      if (!needsNormal[v]) continue;
      const double len = glm::length(accum[v]);
      // Vertices used by no (non-degenerate) triangle get an arbitrary unit normal.
      out->normals[base + v] =
          len > 0.0 && std::isfinite(len) ? glm::vec3(accum[v] / len) : glm::vec3(0, 0, 1);
    }
  } else if (anyNeeded && !warnedZeroNormals_) {
    warnedZeroNormals_ = true;
    warn(path_ +
         ": some vertices have no usable normal and generateNormalsIfMissing is off; they get (0,0,0)");
  }
  if (zeroNormals > 0) {
    warn(where + ": " + str(uint64_t{zeroNormals}) + " zero-length normal(s) replaced" +
         (options_.generateNormalsIfMissing ? " by generated normals" : " by (0,0,0)"));
  }

  // Optional attributes: pad earlier primitives with defaults when the first one that has them shows up.
  if (!prim.uvs.empty()) {
    out->uvs.resize(base, glm::vec2(0.0f));
    out->uvs.insert(out->uvs.end(), prim.uvs.begin(), prim.uvs.end());
  }
  if (!prim.colors.empty()) {
    out->colors.resize(base, 0xFFFFFFFFu);
    out->colors.insert(out->colors.end(), prim.colors.begin(), prim.colors.end());
  }
  if (!prim.uvs1.empty()) {
    out->uvs1.resize(base, glm::vec2(0.0f));
    out->uvs1.insert(out->uvs1.end(), prim.uvs1.begin(), prim.uvs1.end());
  }
  if (!prim.tangents.empty()) {
    out->tangents.resize(base, glm::vec4(0.0f));
    for (const glm::vec4& t : prim.tangents) out->tangents.push_back(transformTangent(linear, det, t));
  }
  return {};
}

Result<Importer::NodeMesh> Importer::nodeMesh(int nodeIndex) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  NodeMesh out;
  out.where = path_ + ": node " + str(nodeIndex) + named(node.name);
  if (node.mesh < 0) return out;
  if (static_cast<size_t>(node.mesh) >= model_.meshes.size()) {
    return malformed(out.where + ": mesh " + str(node.mesh) + " does not exist");
  }
  out.mesh = &model_.meshes[static_cast<size_t>(node.mesh)];
  auto prims = decodedMesh(node.mesh);
  if (!prims) return prims.error();
  out.prims = *prims;
  out.weights = node.weights.empty() ? &out.mesh->weights : &node.weights;
  if (!allFinite(*out.weights)) return malformed(out.where + ": non-finite morph weights");
  return out;
}

Status Importer::emitNode(int nodeIndex, const glm::dmat4& world, MeshSource* out) {
  auto resolved = nodeMesh(nodeIndex);
  if (!resolved) return resolved.error();
  if (!resolved->mesh) return {};
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  const std::string& nodeWhere = resolved->where;
  const tinygltf::Mesh& mesh = *resolved->mesh;
  const std::vector<DecodedPrimitive>* const* prims = &resolved->prims;
  const std::vector<double>& weights = *resolved->weights;
  for (size_t p = 0; p < (*prims)->size(); ++p) {
    const DecodedPrimitive& prim = (**prims)[p];
    if (prim.skipped) {
      ++primitivesSkipped;
      continue;
    }
    const std::string where =
        nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + " primitive " + str(uint64_t{p});
    if (Status s = emitPrimitive(prim, world, weights, where, out); !s) return s;
    ++primitivesImported;
  }
  return {};
}

// Depth-first walk of the default scene with an explicit stack (no recursion depth limit from the file),
// calling visit(nodeIndex, world) for every node in document order. glTF node graphs are disjoint trees, so a
// node met twice means a cycle or a shared child: refuse rather than loop or explode. `sceneLabel` receives a
// description of the roots for messages.
template <typename Visit>
Status Importer::walkScene(Visit&& visit, std::string* sceneLabel) {
  if (Status s = checkRequiredExtensions(); !s) return s;
  if (Status s = checkNodeGraph(); !s) return s;
  meshCache_.resize(model_.meshes.size());
  const size_t nodeCount = model_.nodes.size();

  // Root nodes: the chosen scene's, or every parentless node when the file has no scenes.
  std::vector<int> roots;
  if (!model_.scenes.empty()) {
    int scene = model_.defaultScene;
    if (scene < 0) scene = 0;
    if (static_cast<size_t>(scene) >= model_.scenes.size()) {
      return malformed(path_ + ": default scene " + str(scene) + " does not exist");
    }
    roots = model_.scenes[static_cast<size_t>(scene)].nodes;
    *sceneLabel = "scene " + str(scene);
  } else {
    std::vector<uint8_t> hasParent(nodeCount, 0);
    for (const tinygltf::Node& node : model_.nodes) {
      for (int child : node.children) {
        if (child >= 0 && static_cast<size_t>(child) < nodeCount) hasParent[static_cast<size_t>(child)] = 1;
      }
    }
    for (size_t i = 0; i < nodeCount; ++i) {
      if (!hasParent[i]) roots.push_back(static_cast<int>(i));
    }
    *sceneLabel = "root nodes (file has no scenes)";
  }

  std::vector<uint8_t> visited(nodeCount, 0);
  std::vector<std::pair<int, glm::dmat4>> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, glm::dmat4(1.0));
  while (!stack.empty()) {
    auto [nodeIndex, parentWorld] = stack.back();
    stack.pop_back();
    if (nodeIndex < 0 || static_cast<size_t>(nodeIndex) >= nodeCount) {
      return malformed(path_ + ": node " + str(nodeIndex) + " does not exist (referenced by " + *sceneLabel +
                       " or a parent node)");
    }
    const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
    if (visited[static_cast<size_t>(nodeIndex)]) {
      return malformed(path_ + ": node " + str(nodeIndex) + named(node.name) +
                       " is reached twice (node graph has a cycle or a node with several parents)");
    }
    visited[static_cast<size_t>(nodeIndex)] = 1;
    auto local = localMatrix(nodeIndex);
    if (!local) return local.error();
    const glm::dmat4 world = parentWorld * *local;
    if (!isFinite(world))
      return malformed(path_ + ": node " + str(nodeIndex) + named(node.name) + ": non-finite transform");
    if (Status s = visit(nodeIndex, world); !s) return s;
    for (auto it = node.children.rbegin(); it != node.children.rend(); ++it) stack.emplace_back(*it, world);
  }
  return {};
}

// glTF nodes form disjoint trees: every node has at most one parent and no node is its own ancestor. Checked
// over ALL the file's nodes, whether or not the default scene reaches them (a child index that does not
// exist is reported by walkScene when reached).
Status Importer::checkNodeGraph() {
  const size_t n = model_.nodes.size();
  std::vector<int> parent(n, -1);
  for (size_t i = 0; i < n; ++i) {
    for (const int child : model_.nodes[i].children) {
      if (child < 0 || static_cast<size_t>(child) >= n) continue;
      const size_t c = static_cast<size_t>(child);
      if (c == i) {
        return malformed(path_ + ": node " + str(child) + named(model_.nodes[c].name) +
                         " is its own child (the node graph has a cycle)");
      }
      if (parent[c] >= 0) {
        return malformed(path_ + ": node " + str(child) + named(model_.nodes[c].name) + " has several parents (nodes " +
                         str(parent[c]) + " and " + str(uint64_t{i}) + ")");
      }
      parent[c] = static_cast<int>(i);
    }
  }
  // One parent each: a cycle is a loop of parent links. Walk up from every node; 1 = on this walk, 2 = known
  // to end at a root.
  std::vector<uint8_t> state(n, 0);
  std::vector<size_t> walk;
  for (size_t i = 0; i < n; ++i) {
    walk.clear();
    int v = static_cast<int>(i);
    while (v >= 0 && state[static_cast<size_t>(v)] == 0) {
      state[static_cast<size_t>(v)] = 1;
      walk.push_back(static_cast<size_t>(v));
      v = parent[static_cast<size_t>(v)];
    }
    if (v >= 0 && state[static_cast<size_t>(v)] == 1) {
      return malformed(path_ + ": node " + str(v) + named(model_.nodes[static_cast<size_t>(v)].name) +
                       " is its own ancestor (the node graph has a cycle)");
    }
    for (const size_t w : walk) state[w] = 2;
  }
  return {};
}

// An axis-aligned box (already transformed) must stay within kMaxImportCoordinate.
Status Importer::checkCoordinates(const glm::dvec3& lo, const glm::dvec3& hi, const std::string& where) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(lo[a]) <= kMaxImportCoordinate && std::abs(hi[a]) <= kMaxImportCoordinate)) {
      return malformed(where + ": world-space bounds (" + fmtCoord(lo.x) + ", " + fmtCoord(lo.y) + ", " +
                       fmtCoord(lo.z) + ") .. (" + fmtCoord(hi.x) + ", " + fmtCoord(hi.y) + ", " + fmtCoord(hi.z) +
                       ") reach too far from the origin (|coordinate| > " + fmtCoord(kMaxImportCoordinate) +
                       "): bounds would overflow");
    }
  }
  return {};
}

// Optional streams that some primitive had get their defaults for the vertices of the ones emitted after it.
void padOptionalStreams(MeshSource* m) {
  const size_t n = m->positions.size();
  if (!m->uvs.empty()) m->uvs.resize(n, glm::vec2(0.0f));
  if (!m->colors.empty()) m->colors.resize(n, 0xFFFFFFFFu);
  if (!m->uvs1.empty()) m->uvs1.resize(n, glm::vec2(0.0f));
  if (!m->tangents.empty()) m->tangents.resize(n, glm::vec4(0.0f));
}

Result<MeshSource> Importer::run() {
  MeshSource out;
  out.name = std::filesystem::path(path_).stem().string();
  std::string sceneLabel;
  Status walked = walkScene(
      [&](int nodeIndex, const glm::dmat4& world) -> Status {
        auto worlds = meshInstances(nodeIndex, world, false);
        if (!worlds) return worlds.error();
        for (const glm::dmat4& w : *worlds)
          if (Status s = emitNode(nodeIndex, w, &out); !s) return s;
        return {};
      },
      &sceneLabel);
  if (!walked) return walked.error();

  if (out.indices.empty()) {
    return malformed(path_ + ": no triangle geometry in " + sceneLabel + " (" +
                     str(uint64_t{primitivesSkipped}) + " primitive(s) skipped)");
  }
  padOptionalStreams(&out);
  return out;
}

// ---------------------------------------------------------------------------------------------------------
// Scene import (instances)

// A skinned node's skin exists and every primitive it draws has JOINTS_0 / WEIGHTS_0 (glTF requires both).
Status Importer::checkSkinnedNode(int nodeIndex, const std::vector<DecodedPrimitive>& prims,
                                  const std::string& where) {
  const int skin = model_.nodes[static_cast<size_t>(nodeIndex)].skin;
  if (static_cast<size_t>(skin) >= model_.skins.size())
    return malformed(where + ": skin " + str(skin) + " does not exist");
  for (size_t p = 0; p < prims.size(); ++p) {
    if (!prims[p].skipped && prims[p].joints.empty())
      return malformed(where + ": skinned, but primitive " + str(uint64_t{p}) + " has no JOINTS_0 / WEIGHTS_0");
  }
  return {};
}

// Appends a primitive's skin streams to `out` (whose vertices of this primitive start at `base`). Vertices
// without skin data, before or after skinned ones, get joint 0 with weight 1 (only meshes drawn by
// unskinned nodes can mix: checkSkinnedNode refuses it for skinned ones).
void appendSkinStreams(const DecodedPrimitive& prim, size_t base, MeshSource* out) {
  if (prim.joints.empty() && out->joints.empty()) return;
  out->joints.resize(base, glm::u16vec4(0));
  out->weights.resize(base, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  out->joints.insert(out->joints.end(), prim.joints.begin(), prim.joints.end());
  out->weights.insert(out->weights.end(), prim.weights.begin(), prim.weights.end());
  const size_t end = std::max(out->positions.size(), out->joints.size());
  out->joints.resize(end, glm::u16vec4(0));
  out->weights.resize(end, glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
  // Influences 5-8: zero weight (joint 0) for the vertices of primitives with 4 or none, once any has 8.
  if (prim.joints1.empty() && out->joints1.empty()) return;
  out->joints1.resize(base, glm::u16vec4(0));
  out->weights1.resize(base, glm::vec4(0.0f));
  out->joints1.insert(out->joints1.end(), prim.joints1.begin(), prim.joints1.end());
  out->weights1.insert(out->weights1.end(), prim.weights1.begin(), prim.weights1.end());
  out->joints1.resize(end, glm::u16vec4(0));
  out->weights1.resize(end, glm::vec4(0.0f));
}

// Appends a primitive's morph deltas (its vertices start at `base` in `out`) for the mesh's `targetCount`
// targets: a stream that some primitive has is zero for the vertices of those that lack it.
void appendMorphStreams(const DecodedPrimitive& prim, size_t base, size_t targetCount, MeshSource* out) {
  out->morphTargets.resize(targetCount);
  const size_t end = out->positions.size();
  for (size_t t = 0; t < targetCount; ++t) {
    MeshSource::MorphTarget& dst = out->morphTargets[t];
    auto put = [&](std::vector<glm::vec3>& stream, const std::vector<std::vector<glm::vec3>>& deltas) {
      const bool has = t < deltas.size() && !deltas[t].empty();
      if (!has && stream.empty()) return;
      stream.resize(base, glm::vec3(0.0f));
      if (has) stream.insert(stream.end(), deltas[t].begin(), deltas[t].end());
      stream.resize(end, glm::vec3(0.0f));
    };
    put(dst.positions, prim.positionDeltas);
    put(dst.normals, prim.normalDeltas);
    put(dst.tangents, prim.tangentDeltas);
  }
}

// KHR_lights_punctual: a node's {"extensions": {"KHR_lights_punctual": {"light": i}}} places model.lights[i] at
// the node's world position; spot and directional lights shine along the node's -Z (through the world matrix's
// linear part, renormalised: the extension ignores the node's scale).
Status Importer::emitNodeLight(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  auto ext = node.extensions.find("KHR_lights_punctual");
  if (ext == node.extensions.end() || !ext->second.Has("light")) return {};
  const std::string nodeWhere = path_ + ": node " + str(nodeIndex) + named(node.name);
  const tinygltf::Value& lightValue = ext->second.Get("light");
  const int index = indexValue(lightValue, model_.lights.size());
  if (index < 0)
    return malformed(nodeWhere + ": KHR_lights_punctual light " + numberText(lightValue) + " out of range");
  const tinygltf::Light& l = model_.lights[static_cast<size_t>(index)];
  const std::string where = nodeWhere + ": KHR_lights_punctual light " + str(index) + named(l.name);
  PointLight p;
  if (l.type == "point") {
    p.type = LightType::Point;
  } else if (l.type == "spot") {
    p.type = LightType::Spot;
  } else if (l.type == "directional") {
    p.type = LightType::Directional;
  } else {
    warn(where + ": unknown type '" + l.type + "'; light skipped");
    return {};
  }
  p.position = glm::dvec3(world[3]);
  if (!l.color.empty() && l.color.size() != 3) return malformed(where + ": color must have 3 elements");
  if (l.color.size() == 3) p.color = glm::vec3(float(l.color[0]), float(l.color[1]), float(l.color[2]));
  p.intensity = float(l.intensity);
  // A directional light has no position, so no range (the extension says range is for point and spot lights).
  p.range = p.type == LightType::Directional ? 0.0f : float(l.range);
  if (!(l.range >= 0.0)) return malformed(where + ": negative or non-finite range " + fmtCoord(l.range));
  if (p.type != LightType::Point) {
    const glm::dvec3 d = glm::dmat3(world) * glm::dvec3(0.0, 0.0, -1.0);
    const double len = glm::length(d);
    if (!(len > 0.0) || !std::isfinite(len))
      return malformed(where + ": the node's transform maps -Z to a zero or non-finite direction");
    p.direction = glm::vec3(d / len);
  }
  if (p.type == LightType::Spot) {
    const double inner = l.spot.innerConeAngle, outer = l.spot.outerConeAngle;
    if (!(inner >= 0.0 && inner < outer && outer <= std::numbers::pi / 2))
      return malformed(where + ": spot innerConeAngle " + fmtCoord(inner) + " / outerConeAngle " + fmtCoord(outer) +
                       " (need 0 <= inner < outer <= pi/2)");
    p.innerConeAngle = float(inner);
    p.outerConeAngle = float(outer);
  }
  if (Status s = validatePointLights({p}); !s) return malformed(where + ": " + s.error().message);
  scene->pointLights.push_back(p);
  return {};
}

// A node's light (once, at the node) and its mesh: once, or once per EXT_mesh_gpu_instancing instance.
Status Importer::emitSceneNode(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  if (Status s = emitNodeLight(nodeIndex, world, scene); !s) return s;
  auto worlds = meshInstances(nodeIndex, world, true);
  if (!worlds) return worlds.error();
  for (const glm::dmat4& w : *worlds)
    if (Status s = emitSceneMesh(nodeIndex, w, scene); !s) return s;
  return {};
}

Result<std::vector<glm::dmat4>> Importer::meshInstances(int nodeIndex, const glm::dmat4& world, bool sceneImport) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  auto ext = node.extensions.find(kInstancingExt);
  if (ext == node.extensions.end()) return std::vector<glm::dmat4>{world};
  const std::string where = path_ + ": node " + str(nodeIndex) + named(node.name) + " " + kInstancingExt;
  // A mesh index that does not exist is reported by nodeMesh (emitNode / emitSceneMesh), with the node.
  if (node.mesh >= 0 && static_cast<size_t>(node.mesh) >= model_.meshes.size()) return std::vector<glm::dmat4>{world};
  // The extension instances a mesh; on a node without one it has nothing to instance.
  if (node.mesh < 0) {
    warn(where + ": the node has no mesh; extension ignored");
    return std::vector<glm::dmat4>{world};
  }
  // Skinned and animated nodes are drawn through a skin whose joints carry the node's transform, which has no
  // place for a per-instance one: such a node is imported once, as the extension's fallback (the plain node).
  const bool animated = node.skin >= 0 || (sceneImport && (movingNodes_.count(nodeIndex) > 0 ||
                                                           morphAnimatedNodes_.count(nodeIndex) > 0));
  if (animated) {
    const std::string why = "instancing a skinned or animated node is not supported";
    if (instancingRequired_) return makeError(ErrorCode::Unsupported, where + ": " + why);
    warn(where + ": " + why + "; the node is imported once, without its instances");
    return std::vector<glm::dmat4>{world};
  }
  if (!ext->second.IsObject() || !ext->second.Get("attributes").IsObject())
    return malformed(where + ": 'attributes' must be an object");
  const tinygltf::Value& attributes = ext->second.Get("attributes");
  struct Stream {
    const char* semantic;
    AttributeKind kind;
    int components;
    std::vector<float> values;
    int accessor = -1;
  };
  Stream streams[3] = {{"TRANSLATION", AttributeKind::InstanceVec3, 3, {}},
                       {"ROTATION", AttributeKind::InstanceRotation, 4, {}},
                       {"SCALE", AttributeKind::InstanceVec3, 3, {}}};
  std::optional<uint64_t> count;
  int countAccessor = -1;
  const char* countSemantic = "";
  for (Stream& st : streams) {
    if (!attributes.Has(st.semantic)) continue;
    const tinygltf::Value& index = attributes.Get(st.semantic);
    if (!index.IsNumber()) return malformed(where + ": attribute " + st.semantic + " is not an accessor index");
    st.accessor = indexValue(index, model_.accessors.size());
    if (st.accessor < 0)
      return malformed(where + " accessor " + numberText(index) + " (" + st.semantic + "): accessor does not exist");
    const std::string aw = where + " accessor " + str(st.accessor) + " (" + st.semantic + ")";
    const uint64_t n = model_.accessors[static_cast<size_t>(st.accessor)].count;
    if (n == 0 || n > kMaxInstancesPerNode)
      return malformed(aw + ": instance count " + str(n) + " is not in [1, " + str(kMaxInstancesPerNode) + "]");
    if (count && *count != n)
      return malformed(aw + ": count " + str(n) + " differs from accessor " + str(countAccessor) + " (" +
                       countSemantic + ") count " + str(*count) + " (every instance attribute has one per instance)");
    count = n;
    countAccessor = st.accessor;
    countSemantic = st.semantic;
    int components = 0;
    if (Status s = readFloats(st.accessor, st.kind, aw, &st.values, &components); !s) return s.error();
    for (size_t i = 0; i < st.values.size(); ++i)
      if (!std::isfinite(st.values[i]))
        return malformed(aw + ": instance " + str(uint64_t{i / static_cast<size_t>(st.components)}) +
                         " has a non-finite value (NaN or Inf)");
  }
  if (!count) {  // only custom (underscore) attributes, or none: nothing moves the instances
    warn(where + ": no TRANSLATION, ROTATION or SCALE attribute; the node is imported once");
    return std::vector<glm::dmat4>{world};
  }
  // The transforms here, then (scene import) one ImportedInstance per instance and material group; the
  // flattened import charges its vertex copies in emitPrimitive.
  const uint64_t groups = model_.meshes[static_cast<size_t>(node.mesh)].primitives.size();
  const uint64_t perInstance = sizeof(glm::dmat4) + (sceneImport ? groups * sizeof(ImportedInstance) : 0);
  if (Status s = budget_->charge(*count * perInstance, where); !s) return s.error();
  std::vector<glm::dmat4> out(*count);
  for (uint64_t i = 0; i < *count; ++i) {
    // Each instance's T * R * S, composed like a node's TRS (localMatrix), after the node's world transform.
    glm::dmat3 rs(1.0);
    if (!streams[1].values.empty()) {
      const float* q = &streams[1].values[i * 4];
      const double x = q[0], y = q[1], z = q[2], w = q[3];
      const double len = std::sqrt(x * x + y * y + z * z + w * w);
      if (!(len > 0.0))
        return malformed(where + " accessor " + str(streams[1].accessor) + " (ROTATION): instance " + str(i) +
                         " has a zero-length rotation quaternion");
      rs = quaternionMatrix(x / len, y / len, z / len, w / len);  // exporters write slightly non-unit values
    }
    if (!streams[2].values.empty())
      for (int c = 0; c < 3; ++c) rs[c] *= double(streams[2].values[i * 3 + static_cast<uint64_t>(c)]);
    glm::dmat4 local(rs);
    if (!streams[0].values.empty()) {
      const float* t = &streams[0].values[i * 3];
      local[3] = glm::dvec4(t[0], t[1], t[2], 1.0);
    }
    out[i] = world * local;
    if (!isFinite(out[i]))
      return malformed(where + ": instance " + str(i) + " has a non-finite transform after the node's");
  }
  return out;
}

// Adds one instance of node `nodeIndex`'s mesh at `world` to `scene`: one per material group of its mesh.
Status Importer::emitSceneMesh(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  auto resolved = nodeMesh(nodeIndex);
  if (!resolved) return resolved.error();
  if (!resolved->mesh) return {};
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  const std::string& nodeWhere = resolved->where;
  const tinygltf::Mesh& mesh = *resolved->mesh;
  const std::vector<DecodedPrimitive>* const* prims = &resolved->prims;
  const std::vector<double>& weights = *resolved->weights;

  const double det = glm::determinant(glm::dmat3(world));
  // Not just det == 0: validateScene() rejects objects with |det| < 1e-30 as degenerate, so a node scaled by
  // e.g. 1e-11 on every axis (det 1e-33) must be skipped here too, or a scene that imports would fail to
  // validate after buildImportedScene() (found by GltfFuzz; regression: GltfFuzz.NearlySingularNodeIsSkipped).
  if (!(std::abs(det) >= 1e-30)) {
    warn(nodeWhere + ": zero-scale (singular) transform; instance skipped");
    return {};
  }
  const bool mirrored = det < 0.0;
  if (node.skin >= 0) {
    if (Status s = checkSkinnedNode(nodeIndex, **prims, nodeWhere); !s) return s;
  }
  // Morph targets stay deltas (not baked) when a clip animates this node's weights.
  size_t morphTargets = 0;
  for (const DecodedPrimitive& prim : **prims)
    if (!prim.skipped) morphTargets = std::max(morphTargets, prim.positionDeltas.size());
  const bool morphed = morphTargets > 0 && morphAnimatedNodes_.count(nodeIndex) > 0;
  // An unskinned node whose weights or global transform a clip animates is skinned with a one-joint skin whose
  // joint is the node itself (identity inverse bind): the joint's global matrix is exactly the node transform
  // glTF applies to an unskinned mesh, so rigid node animations (CesiumMilkTruck's wheels) play through the
  // skinning pass, with its per-frame bounds, like skinned meshes.
  const bool oneJoint = node.skin < 0 && (morphed || movingNodes_.count(nodeIndex) > 0);
  static const std::vector<double> kUnmorphed;

  // Material groups in order of first appearance among the primitives.
  std::vector<int> groups;
  for (const tinygltf::Primitive& p : mesh.primitives) {
    if (p.material >= 0 && static_cast<size_t>(p.material) >= model_.materials.size()) {
      return malformed(nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + ": material " +
                       str(p.material) + " does not exist");
    }
    if (std::find(groups.begin(), groups.end(), p.material) == groups.end()) groups.push_back(p.material);
  }

  for (const int gltfMaterial : groups) {
    SceneMeshKey key{node.mesh, gltfMaterial, mirrored, weights, morphed, oneJoint};
    auto found = sceneMeshes_.find(key);
    uint32_t meshIndex = 0;
    uint32_t groupPrimitives = 0;
    for (size_t p = 0; p < (*prims)->size(); ++p) {
      if (mesh.primitives[p].material == gltfMaterial && !(**prims)[p].skipped) ++groupPrimitives;
    }
    if (found == sceneMeshes_.end()) {
      ImportedMesh im;
      im.gltfMesh = node.mesh;
      im.mirrored = mirrored;
      if (gltfMaterial >= 0) {
        im.material = static_cast<uint32_t>(gltfMaterial);
      } else {
        if (!defaultMaterial_) {
          defaultMaterial_ = static_cast<uint32_t>(scene->materials.size());
          Material m;
          m.name = "default";
          scene->materials.push_back(m);
        }
        im.material = *defaultMaterial_;
      }
      im.source.name = mesh.name.empty() ? "mesh" + str(node.mesh) : mesh.name;
      if (groups.size() > 1) im.source.name += "/" + scene->materials[im.material].name;
      if (mirrored) im.source.name += " (mirrored)";
      // Object space: identity transform. Normals are generated (when missing) from the file's winding.
      for (size_t p = 0; p < (*prims)->size(); ++p) {
        const DecodedPrimitive& prim = (**prims)[p];
        if (mesh.primitives[p].material != gltfMaterial || prim.skipped) continue;
        const std::string where =
            nodeWhere + " mesh " + str(node.mesh) + named(mesh.name) + " primitive " + str(uint64_t{p});
        const size_t base = im.source.positions.size();
        if (Status s = emitPrimitive(prim, glm::dmat4(1.0), morphed ? kUnmorphed : weights, where, &im.source); !s)
          return s;
        appendSkinStreams(prim, base, &im.source);
        if (morphed) appendMorphStreams(prim, base, morphTargets, &im.source);
      }
      appendSkinStreams(DecodedPrimitive{}, im.source.positions.size(), &im.source);  // pad to the end
      if (morphed) {
        if (weights.size() != morphTargets)
          warn(nodeWhere + ": " + str(uint64_t{weights.size()}) + " morph weights for " + str(uint64_t{morphTargets}) +
               " targets; missing ones are 0");
        im.source.morphWeights.assign(morphTargets, 0.0f);
        for (size_t t = 0; t < morphTargets && t < weights.size(); ++t)
          im.source.morphWeights[t] = static_cast<float>(weights[t]);
      }
      if (oneJoint) {  // every vertex follows joint 0 of the node's one-joint skin
        im.source.joints.assign(im.source.positions.size(), glm::u16vec4(0));
        im.source.weights.assign(im.source.positions.size(), glm::vec4(1.0f, 0.0f, 0.0f, 0.0f));
        im.source.joints1.clear();
        im.source.weights1.clear();
      }
      padOptionalStreams(&im.source);
      if (mirrored) {
        for (size_t i = 0; i + 2 < im.source.indices.size(); i += 3)
          std::swap(im.source.indices[i + 1], im.source.indices[i + 2]);
        // The instance transform mirrors: see transformTangent. Baked here so shaders need no det sign.
        for (glm::vec4& t : im.source.tangents) t.w = t.w == 0.0f ? 0.0f : -t.w;
      }
      if (im.source.indices.empty()) {
        meshIndex = std::numeric_limits<uint32_t>::max();  // every primitive of the group was skipped
      } else {
        meshIndex = static_cast<uint32_t>(scene->meshes.size());
        scene->meshes.push_back(std::move(im));
      }
      found = sceneMeshes_.emplace(std::move(key), meshIndex).first;
    }
    meshIndex = found->second;
    if (meshIndex != std::numeric_limits<uint32_t>::max()) {
      // The instance's world-space box: its mesh's object-space box (cached per mesh) through `world`.
      if (meshBoxes_.size() <= meshIndex) meshBoxes_.resize(meshIndex + 1);
      auto& box = meshBoxes_[meshIndex];
      if (!box) {
        glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        for (const glm::vec3& p : scene->meshes[meshIndex].source.positions) {
          lo = glm::min(lo, glm::dvec3(p));
          hi = glm::max(hi, glm::dvec3(p));
        }
        box = std::pair{lo, hi};
      }
      glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
      for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 c((corner & 1) ? box->second.x : box->first.x, (corner & 2) ? box->second.y : box->first.y,
                           (corner & 4) ? box->second.z : box->first.z);
        const glm::dvec3 w(world * glm::dvec4(c, 1.0));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
      if (Status s = checkCoordinates(lo, hi, nodeWhere); !s) return s;
    }
    // Counted per primitive instance, like importGltfMesh.
    uint32_t groupSkipped = 0;
    for (size_t p = 0; p < (*prims)->size(); ++p) {
      if (mesh.primitives[p].material == gltfMaterial && (**prims)[p].skipped) ++groupSkipped;
    }
    primitivesSkipped += groupSkipped;
    if (meshIndex == std::numeric_limits<uint32_t>::max()) continue;
    primitivesImported += groupPrimitives;
    ImportedInstance inst;
    inst.mesh = meshIndex;
    inst.material = scene->meshes[meshIndex].material;
    inst.transform = world;
    inst.node = nodeIndex;
    inst.skin = node.skin >= 0 ? node.skin : -1;
    inst.morphed = morphed;
    if (oneJoint) {  // glTF applies the node's world matrix: a joint at the node does the same
      auto [it, added] = nodeSkins_.emplace(nodeIndex, int32_t(scene->skins.size()));
      if (added) {
        Skin skin;
        skin.name = (morphed ? "morph " : "node ") + (node.name.empty() ? "node " + str(nodeIndex) : node.name);
        skin.joints = {static_cast<uint32_t>(nodeIndex)};
        skin.inverseBindMatrices = {glm::dmat4(1.0)};
        scene->skins.push_back(std::move(skin));
      }
      inst.skin = it->second;
    }
    scene->instances.push_back(inst);
  }
  return {};
}

Result<ImportedScene> Importer::runScene() {
  ImportedScene scene;
  scene.name = std::filesystem::path(path_).stem().string();
  const WarnFn warnFn = [this](const std::string& message) { warn(message); };
  if (Status s = importMaterials(model_, path_, warnFn, &scene.materials); !s) return s.error();
  if (Status s = collectImages(model_, path_, references_, &scene.images); !s) return s.error();
  const ReadFloats read = [this](int accessor, const std::string& where, std::vector<float>* out) {
    int n = 0;
    return readFloats(accessor, AttributeKind::Unchecked, where, out, &n);
  };
  if (Status s = importAnimationData(model_, path_, read, warnFn, &scene); !s) return s.error();
  for (const AnimationClip& clip : scene.animations)
    for (const AnimationChannel& c : clip.channels)
      (c.path == AnimationPath::Weights ? morphAnimatedNodes_ : movingNodes_).insert(static_cast<int>(c.node));
  // A node moves when a TRS channel targets it or any of its ancestors (the hierarchy has no cycles: checked).
  if (!movingNodes_.empty()) {
    for (size_t n = 0; n < scene.nodes.size(); ++n) {
      for (int32_t a = int32_t(n); a >= 0; a = scene.nodes[size_t(a)].parent) {
        if (movingNodes_.count(a)) {
          movingNodes_.insert(int(n));
          break;
        }
      }
    }
  }
  std::string sceneLabel;
  Status walked = walkScene(
      [&](int nodeIndex, const glm::dmat4& world) { return emitSceneNode(nodeIndex, world, &scene); },
      &sceneLabel);
  if (!walked) return walked.error();
  if (Status s = checkSkinnedInstances(scene, path_); !s) return s.error();
  if (scene.instances.empty()) {
    return malformed(path_ + ": no triangle geometry in " + sceneLabel + " (" +
                     str(uint64_t{primitivesSkipped}) + " primitive(s) skipped)");
  }
  return scene;
}

}  // namespace

namespace {
// Shared by both entry points: load, run one importer method, report, and keep every exception from
// tinygltf/nlohmann (allocation failure, pathological JSON) inside the engine boundary.
template <typename T>
Result<T> importWith(const std::string& path, const GltfImportOptions& options, GltfImportReport* report,
                     Result<T> (Importer::*run)()) {
  GltfImportReport localReport;
  GltfImportReport& rep = report ? *report : localReport;
  rep = GltfImportReport{};
  try {
    MemoryBudget budget(options.maxMemoryBytes);
    tinygltf::Model model;
    LoadedReferences references;
    if (Status s = loadModel(path, options, &budget, &model, &references, &rep.warnings); !s) return s.error();
    Importer importer(path, model, options, references, &budget, &rep.warnings);
    Result<T> result = (importer.*run)();
    rep.primitivesImported = importer.primitivesImported;
    rep.primitivesSkipped = importer.primitivesSkipped;
    return result;
  } catch (const std::bad_alloc&) {
    return makeError(ErrorCode::CapacityExceeded, path + ": out of memory while importing");
  } catch (const std::exception& e) {
    return malformed(path + ": " + e.what());
  }
}
}  // namespace

Result<MeshSource> importGltfMesh(const std::string& path, const GltfImportOptions& options,
                                  GltfImportReport* report) {
  return importWith<MeshSource>(path, options, report, &Importer::run);
}

Result<ImportedScene> importGltfScene(const std::string& path, const GltfImportOptions& options,
                                      GltfImportReport* report) {
  return importWith<ImportedScene>(path, options, report, &Importer::runScene);
}

}  // namespace visbuf
