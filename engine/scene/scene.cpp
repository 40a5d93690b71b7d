#include "visbuf/scene/scene.h"

#include <algorithm>
#include <cmath>

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

glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object) {
  return objectBoundsWorld(scene, object, maxScaleOf(object.transform));
}

glm::dvec4 objectBoundsWorld(const Scene& scene, const Object& object, double maxScale) {
  const glm::vec4 s = scene.meshes[object.mesh].boundsSphere;
  glm::dvec3 c = glm::dvec3(object.transform * glm::dvec4(glm::dvec3(s), 1.0));
  return {c, double(s.w) * maxScale};
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
  if (!(scene.lightIntensity >= 0.0f) || !std::isfinite(scene.lightIntensity))
    return makeError(ErrorCode::MalformedInput, "directional light: intensity must be finite and >= 0");
  return validateSceneAnimation(scene);
}

std::array<const TextureRef*, kTextureSlotCount> textureSlots(const Material& m) {
  return {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture, &m.occlusionTexture, &m.emissiveTexture};
}

std::array<TextureRef*, kTextureSlotCount> textureSlots(Material& m) {
  return {&m.baseColorTexture, &m.metallicRoughnessTexture, &m.normalTexture, &m.occlusionTexture, &m.emissiveTexture};
}

ColorSpace textureSlotColorSpace(size_t slot) {
  return slot == 0 || slot == 4 ? ColorSpace::Srgb : ColorSpace::Linear;
}

}  // namespace visbuf
