// glTF importer (gltf_import.h): buffer views (plain and EXT_meshopt_compression), accessor plans with every
// offset, count and stride range-checked, and the typed reads (floats, vec3, indices, texcoords, tangents)
// that the primitive decoder and EXT_mesh_gpu_instancing build on.

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

namespace {

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

}  // namespace

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

  // Filled from a Draco stream (gltf_draco.cpp): the accessor's bufferView and byteOffset, if any, are the
  // uncompressed fallback and are ignored, as the extension says; the decode has checked the count.
  if (auto fill = dracoFills_.find(index); fill != dracoFills_.end()) {
    if (acc.sparse.isSparse) return malformed(where + ": an accessor filled from a Draco stream cannot be sparse");
    if (fill->second.bytes.size() != plan.count * plan.elementSize) {
      return malformed(where + ": count " + str(plan.count) + " does not match the Draco stream's data");
    }
    plan.dense = fill->second.bytes.data();
    plan.stride = plan.elementSize;
    return plan;
  }
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
    return makeError(ErrorCode::CapacityExceeded,
                     where + ": count " + str(plan.count) + " without a bufferView (all zeros but " +
                         str(uint64_t(acc.sparse.isSparse ? acc.sparse.count : 0)) +
                         " sparse values) exceeds the limit of " + str(kMaxViewlessAccessorCount) +
                         " elements for an accessor whose data the file does not hold");
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

}  // namespace visbuf::gltf_detail
