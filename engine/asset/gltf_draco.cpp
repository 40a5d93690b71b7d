// glTF importer (gltf_import.h): KHR_draco_mesh_compression through libdraco. A Draco stream is untrusted input:
// the primitive's accessors (declared counts and types) say what the stream must decode to, the decoder's own
// allocations are bounded (DracoAllocationLimit below), and what it decodes is checked and written into the
// accessors' declared types (Importer::dracoFills_), so that it then goes through the same accessor validation,
// NaN / Inf checks and budgets as any other accessor (planAccessor reads the fills).
//
// What the extension says (and what is done with it):
//   - extension.bufferView holds the stream; extension.attributes maps a semantic of primitive.attributes to the
//     Draco attribute's unique id. Each such accessor gets the decoded point values (point count == accessor
//     count, component count == the accessor type's); the indices accessor gets the decoded faces (face count x 3
//     == its count). The accessors' own bufferView / byteOffset are the uncompressed fallback and are ignored.
//   - Attributes not in extension.attributes (and morph targets, which Draco does not compress: draco_transcoder
//     refuses meshes with targets) are read as usual; they must be in the decoded point order (the extension's
//     implementation note: generators write them from the decompressed data). Their counts are checked against
//     POSITION's like any attribute.
//   - Only TRIANGLES primitives: Draco decodes a triangle list, and the extension's "decoded accordingly" for
//     TRIANGLE_STRIP has no defined meaning for one; such primitives are Unsupported (their uncompressed data is
//     used when the file has it).

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {
namespace {

// ---------------------------------------------------------------------------------------------------------
// Bounding the decoder's allocations. libdraco sizes its arrays from counts in the stream (faces, vertices,
// split symbols, symbols per context, attribute values, rANS tables); 1.5.5 checks the connectivity header's
// counts against each other (tests/hostile_cases/draco.py lies in them), but nothing ties what it decodes to what
// the glTF accessors declare: a 7 KB stream of 80,000 faces behind accessors of 12 faces is decoded in full
// before any count can be compared. The accessors state what a valid stream decodes to; the decoder's working
// set follows from that (measured on draco_transcoder output: 23 bytes per corner plus point component for
// DamagedHelmet's 46k corners, about 90 KiB of tables for small meshes; at most 29 % of the estimate below on the
// sample models), so while this thread decodes, every allocation is counted and the decode is stopped
// (std::bad_alloc, caught in decodeDraco) once the total passes the working set charged to the import budget: the
// count is cumulative (frees are not subtracted), an upper bound of the peak. Time follows: the decoder's loops
// run over arrays it has allocated.
thread_local bool tLimitActive = false;
thread_local uint64_t tLimitBytes = 0;
thread_local uint64_t tAllocatedBytes = 0;

class DracoAllocationLimit {
 public:
  explicit DracoAllocationLimit(uint64_t bytes) {
    tLimitBytes = bytes;
    tAllocatedBytes = 0;
    tLimitActive = true;
  }
  ~DracoAllocationLimit() { tLimitActive = false; }
  DracoAllocationLimit(const DracoAllocationLimit&) = delete;
  DracoAllocationLimit& operator=(const DracoAllocationLimit&) = delete;
  static uint64_t allocated() { return tAllocatedBytes; }
};

}  // namespace
}  // namespace visbuf::gltf_detail

// The program's replaceable global allocation functions: malloc and free, as the defaults, plus the count above
// while a Draco decode runs on this thread. Every form is replaced, so that allocation and release always pair
// (sanitizers replace each form with their own, and check that they pair).
void* operator new(std::size_t size) {
  using namespace visbuf::gltf_detail;
  if (tLimitActive) {
    if (size > tLimitBytes - tAllocatedBytes) throw std::bad_alloc();
    tAllocatedBytes += size;
  }
  for (;;) {
    if (void* p = std::malloc(size != 0 ? size : 1)) return p;
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return ::operator new(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return ::operator new(size, tag); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

namespace visbuf::gltf_detail {
namespace {

// Working-set estimate of one decode (see DracoAllocationLimit): bytes per corner (3 per face) and per decoded
// point component, plus a fixed part for the decoder objects and tables.
constexpr uint64_t kDracoBytesPerCorner = 48;
constexpr uint64_t kDracoBytesPerPointComponent = 32;
constexpr uint64_t kDracoFixedBytes = uint64_t{4} << 20;
// Faces (and points) per byte of stream beyond which the counts are refused unread: a perfectly regular grid,
// Draco's best case, encodes 180,000 faces in 13,265 bytes (draco_encoder -cl 10), 14 per byte.
constexpr uint64_t kMaxDracoElementsPerByte = 1024;
// Point components a stream may hold beyond the ones the primitive names (attributes the file does not use).
constexpr uint64_t kDracoExtraComponents = 8;

int numComponents(int type) { return tinygltf::GetNumComponentsInType(static_cast<uint32_t>(type)); }

// Writes `n` components of decoded value `avi` of `att` into `dst` as the C++ type of glTF componentType `ct`,
// through draco's ConvertValue (range-checked: false when a value does not fit the type).
template <typename T>
bool convertInto(const draco::PointAttribute& att, draco::AttributeValueIndex avi, int n, uint8_t* dst) {
  T values[4];
  if (!att.ConvertValue<T>(avi, static_cast<int8_t>(n), values)) return false;
  std::memcpy(dst, values, sizeof(T) * static_cast<size_t>(n));
  return true;
}
// A normalized integer accessor filled from floating-point Draco values (a decoder that dequantised them):
// glTF's normalisation, c = round(v x MAX) with v clamped to the type's range ([-1, 1] signed, [0, 1] unsigned).
template <typename T>
bool normalizeInto(const draco::PointAttribute& att, draco::AttributeValueIndex avi, int n, uint8_t* dst) {
  float values[4];
  if (!att.ConvertValue<float>(avi, static_cast<int8_t>(n), values)) return false;
  constexpr double kMax = double(std::numeric_limits<T>::max());
  constexpr double kMin = std::is_signed_v<T> ? -1.0 : 0.0;
  for (int c = 0; c < n; ++c) {
    if (!std::isfinite(values[c])) return false;
    const T v = static_cast<T>(std::lround(std::clamp(double(values[c]), kMin, 1.0) * kMax));
    std::memcpy(dst + sizeof(T) * static_cast<size_t>(c), &v, sizeof(T));
  }
  return true;
}
bool convertComponent(int ct, bool normalized, const draco::PointAttribute& att, draco::AttributeValueIndex avi,
                      int n, uint8_t* dst) {
  if (normalized && (att.data_type() == draco::DT_FLOAT32 || att.data_type() == draco::DT_FLOAT64)) {
    switch (ct) {
      case TINYGLTF_COMPONENT_TYPE_BYTE: return normalizeInto<int8_t>(att, avi, n, dst);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalizeInto<uint8_t>(att, avi, n, dst);
      case TINYGLTF_COMPONENT_TYPE_SHORT: return normalizeInto<int16_t>(att, avi, n, dst);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return normalizeInto<uint16_t>(att, avi, n, dst);
    }
  }
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return convertInto<int8_t>(att, avi, n, dst);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return convertInto<uint8_t>(att, avi, n, dst);
    case TINYGLTF_COMPONENT_TYPE_SHORT: return convertInto<int16_t>(att, avi, n, dst);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return convertInto<uint16_t>(att, avi, n, dst);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return convertInto<uint32_t>(att, avi, n, dst);
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return convertInto<float>(att, avi, n, dst);
  }
  return false;
}

// One accessor the stream fills: a named attribute (id >= 0) or the indices (id == -1).
struct Target {
  std::string semantic;
  int accessor = -1;
  int id = -1;
};

}  // namespace

int Importer::primitiveIndices(int mesh, int primitive) const {
  auto it = references_.dracoIndices.find({mesh, primitive});
  if (it != references_.dracoIndices.end()) return it->second;
  return model_.meshes[static_cast<size_t>(mesh)].primitives[static_cast<size_t>(primitive)].indices;
}

Status Importer::decodeDraco(int meshIndex, int primIndex, const std::string& where) {
  const tinygltf::Primitive& prim =
      model_.meshes[static_cast<size_t>(meshIndex)].primitives[static_cast<size_t>(primIndex)];
  const tinygltf::Value& ext = prim.extensions.at(kDracoExt);
  const std::string ew = where + " (" + kDracoExt + ")";
  if (!ext.IsObject()) return malformed(ew + ": the extension is not an object");
  const int view = indexValue(ext.Get("bufferView"), model_.bufferViews.size());
  if (view < 0) return malformed(ew + ": bufferView " + numberText(ext.Get("bufferView")) + " does not exist");
  const tinygltf::Value& attributes = ext.Get("attributes");
  if (!attributes.IsObject()) return malformed(ew + ": 'attributes' is missing or not an object");

  // The accessors to fill, checked before anything is decoded.
  std::vector<Target> targets;
  std::set<int> ids, accessors;
  for (const std::string& semantic : attributes.Keys()) {
    const tinygltf::Value& idValue = attributes.Get(semantic);
    const int id = indexValue(idValue, size_t{std::numeric_limits<int>::max()});
    if (id < 0) return malformed(ew + ": attribute id " + numberText(idValue) + " of " + semantic + " is not valid");
    if (!ids.insert(id).second) return malformed(ew + ": Draco attribute id " + str(id) + " is named twice");
    auto it = prim.attributes.find(semantic);
    if (it == prim.attributes.end()) {
      return malformed(ew + ": " + semantic + " is not an attribute of the primitive");
    }
    if (!accessors.insert(it->second).second) {
      return malformed(ew + ": accessor " + str(it->second) + " (" + semantic + ") is named by two attributes");
    }
    targets.push_back({semantic, it->second, id});
  }
  if (targets.empty()) return malformed(ew + ": 'attributes' names no attribute");
  const int indices = primitiveIndices(meshIndex, primIndex);
  if (indices < 0) return malformed(ew + ": a Draco-compressed primitive needs an indices accessor");
  if (accessors.count(indices) != 0) return malformed(ew + ": indices accessor " + str(indices) + " is also an attribute");
  targets.push_back({"indices", indices, -1});

  // Already decoded (another primitive names the same stream and accessors)?
  bool decoded = true;
  for (const Target& t : targets) {
    auto fill = dracoFills_.find(t.accessor);
    if (fill == dracoFills_.end()) {
      decoded = false;
    } else if (fill->second.view != view || fill->second.id != t.id) {
      return malformed(ew + ": accessor " + str(t.accessor) + " (" + t.semantic +
                       ") is also filled from another Draco stream or attribute");
    }
  }
  if (decoded) return {};

  // Refusals that the uncompressed data, when the file has it, can stand in for.
  auto cannotDecode = [&](Error error) -> Status {
    bool fallback = true;
    for (const std::string& required : model_.extensionsRequired) fallback = fallback && required != kDracoExt;
    for (const Target& t : targets)
      fallback = fallback && model_.accessors[static_cast<size_t>(t.accessor)].bufferView >= 0;
    if (!fallback) return error;
    warn(error.message + "; using the primitive's uncompressed data");
    return {};
  };
  if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
    return cannotDecode(makeError(ErrorCode::Unsupported, ew + ": only TRIANGLES primitives can be Draco-compressed"));
  }

  // What the accessors say the stream decodes to.
  const tinygltf::Accessor& indexAccessor = model_.accessors[static_cast<size_t>(indices)];
  if (indexAccessor.count % 3 != 0) {
    return malformed(ew + ": indices accessor " + str(indices) + " count " + str(uint64_t{indexAccessor.count}) +
                     " is not a multiple of 3 (Draco decodes triangles)");
  }
  const uint64_t faces = indexAccessor.count / 3;
  const uint64_t points = model_.accessors[static_cast<size_t>(targets.front().accessor)].count;
  uint64_t components = kDracoExtraComponents;
  uint64_t fillBytes = 0;
  for (const Target& t : targets) {
    const tinygltf::Accessor& acc = model_.accessors[static_cast<size_t>(t.accessor)];
    const int n = numComponents(acc.type);
    const int size = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType));
    if (n <= 0 || n > 4 || size <= 0) {
      return malformed(ew + ": accessor " + str(t.accessor) + " (" + t.semantic + ") has a type that Draco cannot fill");
    }
    if (t.id >= 0 && acc.count != points) {
      return malformed(ew + ": accessor " + str(t.accessor) + " (" + t.semantic + ") count " +
                       str(uint64_t{acc.count}) + " differs from accessor " + str(targets.front().accessor) + " (" +
                       targets.front().semantic + ") count " + str(points) + " (one Draco point each)");
    }
    if (t.id >= 0) components += static_cast<uint64_t>(n);
    fillBytes += uint64_t{acc.count} * static_cast<uint64_t>(n) * static_cast<uint64_t>(size);
  }
  auto bytes = viewBytes(view, ew);
  if (!bytes) return bytes.error();
  const std::string sw = ew + ": Draco stream (bufferView " + str(view) + ", " + str(bytes->size) + " bytes)";
  // Counts no stream of this size can hold (a bomb: accessors that agree with a lying stream header).
  const uint64_t plausible = kMaxDracoElementsPerByte * (bytes->size + 16);
  if (faces > plausible || points > plausible) {
    return cannotDecode(malformed(sw + ": " + str(faces) + " faces and " + str(points) +
                                  " points are implausible for its size (at most " + str(kMaxDracoElementsPerByte) +
                                  " of each per byte)"));
  }
  // The decoder's working set (counts are at most 2^53 each: validateGltfDocument), then the fills.
  const uint64_t workBytes =
      kDracoFixedBytes + kDracoBytesPerCorner * 3 * faces + kDracoBytesPerPointComponent * points * components;
  if (Status s = budget_->charge(workBytes, ew + ": the Draco decoder's working set"); !s) return s;
  struct Release {
    MemoryBudget* budget;
    uint64_t bytes;
    ~Release() { budget->release(bytes); }
  } release{budget_, workBytes};
  if (Status s = budget_->charge(fillBytes, ew + ": the decoded accessors"); !s) return s;

  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes->data), bytes->size);
  std::unique_ptr<draco::Mesh> mesh;
  {
    auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
    if (!type.ok()) return cannotDecode(malformed(sw + ": " + type.status().error_msg_string()));
    if (type.value() != draco::TRIANGULAR_MESH) return cannotDecode(malformed(sw + " holds a point cloud, not a mesh"));
    buffer.Init(reinterpret_cast<const char*>(bytes->data), bytes->size);
    try {
      DracoAllocationLimit limit(workBytes);
      draco::Decoder decoder;
      auto result = decoder.DecodeMeshFromBuffer(&buffer);
      if (!result.ok()) return cannotDecode(malformed(sw + ": " + result.status().error_msg_string()));
      mesh = std::move(result).value();
    } catch (const std::bad_alloc&) {
      return cannotDecode(malformed(sw + ": the decoder asked for more than " + str(workBytes) +
                                    " bytes, more than a stream of " + str(faces) + " faces and " + str(points) +
                                    " points (the accessors' counts) needs"));
    } catch (const std::exception& e) {  // (std::length_error from a vector sized by the stream)
      return cannotDecode(malformed(sw + ": the decoder failed (" + e.what() + ")"));
    }
  }

  // The decoded mesh against the accessors.
  if (mesh->num_faces() != faces || mesh->num_points() != points) {
    return cannotDecode(malformed(sw + " decodes to " + str(uint64_t{mesh->num_faces()}) + " faces and " +
                                  str(uint64_t{mesh->num_points()}) + " points; the accessors say " + str(faces) +
                                  " faces (indices count / 3) and " + str(points) + " points"));
  }
  std::vector<std::pair<int, std::vector<uint8_t>>> filled;
  for (const Target& t : targets) {
    const tinygltf::Accessor& acc = model_.accessors[static_cast<size_t>(t.accessor)];
    const int n = numComponents(acc.type);
    const uint64_t elementSize =
        static_cast<uint64_t>(n) * static_cast<uint64_t>(tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType)));
    std::vector<uint8_t> out(acc.count * elementSize);
    const std::string aw = sw + ": accessor " + str(t.accessor) + " (" + t.semantic + ")";
    if (t.id < 0) {  // the faces, in the indices accessor's type
      if (n != 1 || (acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                     acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                     acc.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)) {
        return malformed(aw + ": indices must be SCALAR UNSIGNED_BYTE/SHORT/INT");
      }
      const uint64_t maxIndex = elementSize == 4 ? 0xFFFFFFFFu : (uint64_t{1} << (8 * elementSize)) - 1;
      for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
        for (int c = 0; c < 3; ++c) {
          const uint32_t v = mesh->face(f)[c].value();
          if (v >= points || v > maxIndex) {
            return cannotDecode(malformed(aw + ": face " + str(uint64_t{f.value()}) + " index " + str(uint64_t{v}) +
                                          (v >= points ? " is not below the point count " + str(points)
                                                       : " does not fit the accessor's component type")));
          }
          std::memcpy(out.data() + (uint64_t{f.value()} * 3 + static_cast<uint64_t>(c)) * elementSize, &v, elementSize);
        }
      }
      filled.emplace_back(t.accessor, std::move(out));
      continue;
    }
    const draco::PointAttribute* att = mesh->GetAttributeByUniqueId(static_cast<uint32_t>(t.id));
    if (att == nullptr) return cannotDecode(malformed(aw + ": the stream has no attribute with unique id " + str(t.id)));
    if (att->num_components() != n) {
      return cannotDecode(malformed(aw + ": Draco attribute " + str(t.id) + " has " + str(int{att->num_components()}) +
                                    " components; the accessor's type has " + str(n)));
    }
    const uint64_t valueBytes = static_cast<uint64_t>(att->num_components()) *
                                static_cast<uint64_t>(draco::DataTypeLength(att->data_type()));
    const draco::DataBuffer* data = att->buffer();
    const uint64_t dataSize = data != nullptr ? static_cast<uint64_t>(data->data_size()) : 0;
    if (valueBytes == 0 || att->byte_stride() < 0 || att->byte_offset() < 0) {
      return cannotDecode(malformed(aw + ": Draco attribute " + str(t.id) + " has an invalid layout"));
    }
    for (uint64_t p = 0; p < points; ++p) {
      const draco::PointIndex point(static_cast<uint32_t>(p));
      if (!att->is_mapping_identity() && p >= att->indices_map_size()) {
        return cannotDecode(malformed(aw + ": point " + str(p) + " has no value in Draco attribute " + str(t.id)));
      }
      const draco::AttributeValueIndex avi = att->mapped_index(point);
      const uint64_t at = static_cast<uint64_t>(att->byte_offset()) +
                          static_cast<uint64_t>(att->byte_stride()) * uint64_t{avi.value()};
      if (avi.value() >= att->size() || !rangeFits(at, valueBytes, dataSize)) {
        return cannotDecode(malformed(aw + ": point " + str(p) + " maps to value " + str(uint64_t{avi.value()}) +
                                      " outside Draco attribute " + str(t.id) + "'s data"));
      }
      if (!convertComponent(acc.componentType, acc.normalized, *att, avi, n, out.data() + p * elementSize)) {
        return cannotDecode(malformed(aw + ": value " + str(uint64_t{avi.value()}) +
                                      " of Draco attribute " + str(t.id) + " does not fit the accessor's component type"));
      }
    }
    filled.emplace_back(t.accessor, std::move(out));
  }
  for (size_t i = 0; i < filled.size(); ++i) {
    DracoFill& fill = dracoFills_[filled[i].first];
    fill.bytes = std::move(filled[i].second);
    fill.view = view;
    fill.id = targets[i].id;
  }
  return {};
}

}  // namespace visbuf::gltf_detail
