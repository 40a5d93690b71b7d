// glTF importer (gltf_import.h): the cameras of the scene's nodes.

#include <cmath>
#include <numbers>
#include <string>

#include <glm/glm.hpp>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"

namespace visbuf::gltf_detail {

// A node's "camera": model.cameras[i] placed by the node's world matrix with its scale removed (glTF: the camera
// looks down the node's local -Z, +Y up; scale and shear are ignored). The checks are glTF's, with one message each:
// perspective yfov in (0, pi), znear > 0, zfar > znear where given, aspectRatio > 0 where given; orthographic
// xmag, ymag > 0 (glTF forbids 0 and advises against negative: visbuf refuses a mirrored camera too), znear >= 0,
// zfar > znear. The parser stores an absent zfar / aspectRatio as 0, so 0 reads as absent.
Status Importer::emitNodeCamera(int nodeIndex, const glm::dmat4& world, ImportedScene* scene) {
  const tinygltf::Node& node = model_.nodes[static_cast<size_t>(nodeIndex)];
  if (node.camera < 0) return {};
  const std::string nodeWhere = path_ + ": node " + str(nodeIndex) + named(node.name);
  if (static_cast<size_t>(node.camera) >= model_.cameras.size())
    return malformed(nodeWhere + ": camera " + str(node.camera) + " does not exist");
  const tinygltf::Camera& gc = model_.cameras[static_cast<size_t>(node.camera)];
  const std::string where = nodeWhere + ": camera " + str(node.camera) + named(gc.name);
  auto bad = [&](const std::string& what, double v) { return malformed(where + ": " + what + " " + fmtCoord(v)); };
  Camera c;
  if (gc.type == "perspective") {
    const tinygltf::PerspectiveCamera& p = gc.perspective;
    if (!(p.yfov > 0.0 && p.yfov < std::numbers::pi)) return bad("perspective yfov must be in (0, pi) radians, not", p.yfov);
    if (!(p.znear > 0.0 && std::isfinite(p.znear))) return bad("perspective znear must be > 0, not", p.znear);
    if (!(p.zfar == 0.0 || (p.zfar > p.znear && std::isfinite(p.zfar))))
      return bad("perspective zfar must be beyond znear " + fmtCoord(p.znear) + ", not", p.zfar);
    if (!(p.aspectRatio >= 0.0 && std::isfinite(p.aspectRatio)))
      return bad("perspective aspectRatio must be > 0, not", p.aspectRatio);
    c.projection = Projection::Perspective;
    c.fovY = p.yfov;
    c.nearPlane = p.znear;
    c.farPlane = p.zfar > 0.0 ? p.zfar : INFINITY;
    c.aspectRatio = p.aspectRatio;
  } else if (gc.type == "orthographic") {
    const tinygltf::OrthographicCamera& o = gc.orthographic;
    if (!(o.xmag > 0.0 && std::isfinite(o.xmag))) return bad("orthographic xmag must be > 0, not", o.xmag);
    if (!(o.ymag > 0.0 && std::isfinite(o.ymag))) return bad("orthographic ymag must be > 0, not", o.ymag);
    if (!(o.znear >= 0.0 && std::isfinite(o.znear))) return bad("orthographic znear must be >= 0, not", o.znear);
    if (!(o.zfar > o.znear && std::isfinite(o.zfar)))
      return bad("orthographic zfar must be finite and beyond znear " + fmtCoord(o.znear) + ", not", o.zfar);
    c.projection = Projection::Orthographic;
    c.xmag = o.xmag;
    c.ymag = o.ymag;
    c.nearPlane = o.znear;
    c.farPlane = o.zfar;
  } else {
    warn(where + ": unknown type '" + gc.type + "'; camera skipped");
    return {};
  }
  if (Status s = setCameraPose(c, world); !s) return malformed(where + ": the node's transform: " + s.error().message);
  if (Status s = validateCamera(c); !s) return malformed(where + ": " + s.error().message);
  scene->cameras.push_back({gc.name.empty() ? node.name : gc.name, c});
  return {};
}

}  // namespace visbuf::gltf_detail
