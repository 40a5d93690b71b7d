// glTF importer (gltf_import.h): KHR_lights_punctual lights of the scene's nodes.

#include <cmath>
#include <numbers>
#include <string>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

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

}  // namespace visbuf::gltf_detail
