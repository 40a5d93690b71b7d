#include "visbuf/scene/scene.h"
#include "visbuf/scene/clusters.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>

namespace visbuf {

uint64_t Scene::totalTriangles() const {
  uint64_t n = 0;
  for (const Object& o : objects) n += meshes[o.mesh].triangleCount(0);
  return n;
}

double maxScaleOf(const glm::dmat4& m) {
  // Upper bound of the spectral norm of the 3x3 part: sqrt of the Gershgorin bound of the largest
  // eigenvalue of A^T A. Exact for rotation x uniform scale; never below the true value.
  glm::dmat3 a(m);
  glm::dmat3 ata = glm::transpose(a) * a;
  double best = 0.0;
  for (int i = 0; i < 3; ++i)
    best = std::max(best, std::abs(ata[0][i]) + std::abs(ata[1][i]) + std::abs(ata[2][i]));
  return std::sqrt(best) * (1.0 + 1e-6);
}


std::vector<uint32_t> spatialObjectOrder(const Scene& scene) {
  const size_t n = scene.objects.size();
  std::vector<glm::dvec3> centres(n);
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (size_t i = 0; i < n; ++i) {
    const Object& o = scene.objects[i];  // (an unchecked scene's bad mesh reference: the object's origin)
    centres[i] = o.mesh < scene.meshes.size() ? objectCentreWorld(scene, o) : glm::dvec3(o.transform[3]);
    lo = glm::min(lo, centres[i]);
    hi = glm::max(hi, centres[i]);
  }
  const double extent = n ? std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) : 0.0;
  const double cells = double((1u << 21) - 1);
  const double scale = extent > 0.0 && std::isfinite(extent) ? cells / extent : 0.0;  // (non-finite: one cell)
  std::vector<std::pair<uint64_t, uint32_t>> keys(n);
  for (size_t i = 0; i < n; ++i) {
    auto cell = [&](int a) {
      const double q = (centres[i][a] - lo[a]) * scale;
      return std::isfinite(q) ? uint64_t(std::clamp(q, 0.0, cells)) : uint64_t{0};
    };
    keys[i] = {spreadBits3(cell(0)) | spreadBits3(cell(1)) << 1 | spreadBits3(cell(2)) << 2, uint32_t(i)};
  }
  std::sort(keys.begin(), keys.end());  // (equal codes: the lower index first)
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = keys[i].second;
  return order;
}

std::vector<uint32_t> orderObjectsSpatially(Scene& scene) {
  std::vector<uint32_t> order = spatialObjectOrder(scene);
  std::vector<uint32_t> newIndex(order.size());
  std::vector<Object> objects(order.size());
  for (size_t k = 0; k < order.size(); ++k) {
    objects[k] = scene.objects[order[k]];
    newIndex[order[k]] = uint32_t(k);
  }
  scene.objects = std::move(objects);
  for (SkinnedObject& so : scene.skinnedObjects)
    if (so.object < newIndex.size()) so.object = newIndex[so.object];
  for (RigidObject& ro : scene.rigidObjects)
    if (ro.object < newIndex.size()) ro.object = newIndex[ro.object];
  return order;
}

glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object) {
  return objectBoundsWorld(scene, object, maxScaleOf(object.transform));
}

glm::dvec3 objectCentreWorld(const Scene& scene, const Object& object) {
  return glm::dvec3(object.transform * glm::dvec4(glm::dvec3(scene.meshes[object.mesh].boundsSphere), 1.0));
}

glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object, double maxScale) {
  return {objectCentreWorld(scene, object), double(scene.meshes[object.mesh].boundsSphere.w) * maxScale};
}

Status validateScene(const Scene& scene) {
  if (scene.meshes.empty()) return makeError(ErrorCode::MalformedInput, "scene has no meshes");
  if (scene.materials.empty()) return makeError(ErrorCode::MalformedInput, "scene has no materials");
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const Mesh& m = scene.meshes[i];
    if (m.lods.empty() || m.lods.size() > MAX_LODS)
      return makeError(ErrorCode::MalformedInput, fmt::format("mesh {} '{}': {} LODs (1..{})", i, m.name,
                                                              m.lods.size(), MAX_LODS));
    for (const Lod& l : m.lods)
      if (l.indexCount == 0 || l.indexCount % 3 || size_t(l.firstIndex) + l.indexCount > m.indices.size())
        return makeError(ErrorCode::MalformedInput, fmt::format("mesh {} '{}': LOD range out of bounds", i, m.name));
    if ((!m.tangents.empty() && m.tangents.size() != m.vertices.size()) ||
        (!m.uvs1.empty() && m.uvs1.size() != m.vertices.size()))
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("mesh {} '{}': tangent / uv1 stream size differs from the vertex count", i, m.name));
    for (uint32_t idx : m.indices)
      if (idx >= m.vertices.size())
        return makeError(ErrorCode::MalformedInput, fmt::format("mesh {} '{}': index out of range", i, m.name));
  }
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const Object& o = scene.objects[i];
    if (o.mesh >= scene.meshes.size() || o.material >= scene.materials.size())
      return makeError(ErrorCode::MalformedInput, fmt::format("object {}: mesh or material index out of range", i));
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(o.transform[c][r]))
          return makeError(ErrorCode::MalformedInput, fmt::format("object {}: non-finite transform", i));
    if (std::abs(glm::determinant(glm::dmat3(o.transform))) < 1e-30)
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("object {}: degenerate (zero-scale) transform", i));
  }
  if (Status s = validatePointLights(scene.pointLights); !s) return s;
  if (Status s = validateCamera(scene.defaultCamera); !s)
    return makeError(ErrorCode::MalformedInput, "default " + s.error().message);
  for (size_t i = 0; i < scene.cameras.size(); ++i)
    if (Status s = validateCamera(scene.cameras[i].camera); !s)
      return makeError(ErrorCode::MalformedInput, fmt::format("camera {} '{}': {}", i, scene.cameras[i].name,
                                                              s.error().message));
  if (!(scene.lightIntensity >= 0.0f) || !std::isfinite(scene.lightIntensity))
    return makeError(ErrorCode::MalformedInput, "directional light: intensity must be finite and >= 0");
  return validateSceneAnimation(scene);
}

std::array<const TextureRef*, kTextureSlotCount> textureSlots(const Material& m) {
  return {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture,           &m.occlusionTexture,
          &m.emissiveTexture,  &m.clearcoatTexture,         &m.clearcoatRoughnessTexture, &m.clearcoatNormalTexture};
}

std::array<TextureRef*, kTextureSlotCount> textureSlots(Material& m) {
  return {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture,           &m.occlusionTexture,
          &m.emissiveTexture,  &m.clearcoatTexture,         &m.clearcoatRoughnessTexture, &m.clearcoatNormalTexture};
}

ColorSpace textureSlotColorSpace(size_t slot) {
  return slot == TEXTURE_SLOT_BASE_COLOR || slot == TEXTURE_SLOT_EMISSIVE ? ColorSpace::Srgb : ColorSpace::Linear;
}

uint32_t materialFeatures(const Material& m) {
  // (an unlit material shows no coat: the shading returns before it)
  if (m.unlit) return MATERIAL_FEATURE_UNLIT;
  return m.clearcoat > 0.0f ? MATERIAL_FEATURE_CLEARCOAT : 0u;
}

}  // namespace visbuf
