// The table of glTF extensions visbuf knows and the audit of a file's extensions (contract in gltf_extensions.h).

#include "visbuf/asset/gltf_extensions.h"

#include <algorithm>
#include <map>
#include <utility>

#include <nlohmann/json.hpp>

#include "visbuf/asset/uri_resolver.h"

namespace visbuf {
namespace {

using S = GltfExtensionSupport;

// Sorted by name (checked by the unit test: findGltfExtension binary-searches it).
constexpr GltfExtension kExtensions[] = {
    {"ADOBE_materials_thin_transparency", S::Dropped, "", "thin transparency (surfaces render opaque)"},
    {"AGI_articulations", S::Dropped, "", "articulations (the rest pose is drawn)"},
    {"AGI_stk_metadata", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"CESIUM_primitive_outline", S::Dropped, "", "primitive outlines"},
    {"EXT_lights_ies", S::Dropped, "", "IES light profiles (the lights are not drawn)"},
    {"EXT_lights_image_based", S::Dropped, "", "image-based lighting (only punctual lights light the scene)"},
    {"EXT_mesh_features", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"EXT_mesh_gpu_instancing", S::Read, "instances become objects (TRANSLATION / ROTATION / SCALE)", ""},
    {"EXT_meshopt_compression", S::Read, "buffer views decoded by meshoptimizer (fallback buffers never read)", ""},
    {"EXT_structural_metadata", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"EXT_texture_avif", S::Partial, "the texture's fallback PNG/JPEG source is used",
     "AVIF images (a texture without a fallback source is dropped)"},
    {"EXT_texture_webp", S::Partial, "the texture's fallback PNG/JPEG source is used",
     "WebP images (a texture without a fallback source is dropped)"},
    {"FB_geometry_metadata", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"FB_ngon_encoding", S::Read, "triangle order hints for editors: the triangles are drawn as given", ""},
    {"KHR_animation_pointer", S::Dropped, "", "animation channels with pointer targets (their properties stay put)"},
    {"KHR_draco_mesh_compression", S::Read,
     "decoded by libdraco into the accessors it names (TRIANGLES; uncompressed fallback when only used)", ""},
    {"KHR_lights_punctual", S::Read, "directional, point and spot lights (range, cone, colour, intensity)", ""},
    {"KHR_materials_anisotropy", S::Dropped, "", "anisotropic specular (isotropic GGX is used)"},
    {"KHR_materials_clearcoat", S::Read, "clear coat layer: factor, roughness, their textures and the coat normal", ""},
    {"KHR_materials_diffuse_transmission", S::Dropped, "", "diffuse transmission (surfaces render opaque)"},
    {"KHR_materials_dispersion", S::Dropped, "", "dispersion"},
    {"KHR_materials_emissive_strength", S::Read, "emissive factor multiplied by the strength (HDR emission)", ""},
    {"KHR_materials_ior", S::Dropped, "", "the index of refraction (1.5 is used)"},
    {"KHR_materials_iridescence", S::Dropped, "", "thin-film iridescence"},
    {"KHR_materials_pbrSpecularGlossiness", S::Read,
     "converted to metallic-roughness, factors and textures (docs/materials.md states the error)", ""},
    {"KHR_materials_sheen", S::Dropped, "", "the sheen layer"},
    {"KHR_materials_specular", S::Dropped, "", "specular strength and colour (F0 0.04 is used)"},
    {"KHR_materials_transmission", S::Dropped, "", "transmission (surfaces render opaque)"},
    {"KHR_materials_unlit", S::Read, "unlit shading: the base colour as is", ""},
    {"KHR_materials_variants", S::Partial, "each primitive's default material is used",
     "material variants (none can be selected)"},
    {"KHR_materials_volume", S::Dropped, "", "volume attenuation and thickness"},
    {"KHR_mesh_quantization", S::Read, "quantised attributes (normalised and integer components)", ""},
    {"KHR_texture_basisu", S::Partial, "the texture's fallback PNG/JPEG source is used",
     "KTX2 / Basis Universal images (a texture without a fallback source is dropped)"},
    {"KHR_texture_transform", S::Read, "offset, rotation, scale and texCoord override per texture reference", ""},
    {"KHR_xmp", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"KHR_xmp_json_ld", S::Read, "metadata only: nothing rendered depends on it", ""},
    {"MSFT_lod", S::Partial, "the highest-detail mesh and material are used (visbuf builds its own LODs)",
     "the file's LOD chain"},
    {"MSFT_packing_normalRoughnessMetallic", S::Partial, "the core textures are used",
     "the packed normal-roughness-metallic texture"},
    {"MSFT_packing_occlusionRoughnessMetallic", S::Partial, "the core textures are used",
     "the packed occlusion-roughness-metallic textures"},
    {"MSFT_texture_dds", S::Partial, "the texture's fallback PNG/JPEG source is used",
     "DDS images (a texture without a fallback source is dropped)"},
};

bool ignored(const std::vector<std::string>& ignoreRequired, const std::string& name) {
  return std::any_of(ignoreRequired.begin(), ignoreRequired.end(),
                     [&](const std::string& n) { return n == "*" || n == name; });
}

// Every key of every "extensions" object in the document, with the JSON path of its first use (iterative: the
// container check bounds the depth, not the stack).
std::map<std::string, std::string> extensionsFound(const nlohmann::json& doc) {
  std::map<std::string, std::string> found;
  std::vector<std::pair<const nlohmann::json*, std::string>> stack{{&doc, ""}};
  while (!stack.empty()) {
    auto [node, where] = stack.back();
    stack.pop_back();
    if (node->is_object()) {
      for (auto it = node->begin(); it != node->end(); ++it) {
        const std::string at = where + "/" + it.key();
        if (it.key() == "extensions" && it->is_object()) {
          for (auto e = it->begin(); e != it->end(); ++e) found.emplace(e.key(), at);
        }
        if (it->is_structured()) stack.emplace_back(&*it, at);
      }
    } else if (node->is_array()) {
      for (size_t i = 0; i < node->size(); ++i) {
        if ((*node)[i].is_structured()) stack.emplace_back(&(*node)[i], where + "/" + std::to_string(i));
      }
    }
  }
  return found;
}

std::vector<std::string> stringList(const nlohmann::json& doc, const char* key) {
  std::vector<std::string> out;
  auto it = doc.find(key);
  if (it == doc.end() || !it->is_array()) return out;
  for (const nlohmann::json& v : *it)
    if (v.is_string()) out.push_back(v.get<std::string>());
  return out;
}

}  // namespace

std::span<const GltfExtension> gltfExtensions() { return kExtensions; }

const GltfExtension* findGltfExtension(std::string_view name) {
  auto it = std::lower_bound(std::begin(kExtensions), std::end(kExtensions), name,
                             [](const GltfExtension& e, std::string_view n) { return e.name < n; });
  return it != std::end(kExtensions) && it->name == name ? &*it : nullptr;
}

Status auditGltfExtensions(const nlohmann::json& doc, const std::string& path,
                           const std::vector<std::string>& ignoreRequired, std::vector<std::string>* warnings) {
  if (!doc.is_object()) return {};
  const std::vector<std::string> required = stringList(doc, "extensionsRequired");
  for (const std::string& name : required) {
    const GltfExtension* e = findGltfExtension(name);
    if ((e != nullptr && e->support == S::Read) || ignored(ignoreRequired, name)) continue;
    const std::string shown = quoteForMessage(name);
    std::string why = e == nullptr ? "visbuf does not know it"
                                   : "visbuf does not read " + std::string(e->dropped);
    return makeError(ErrorCode::Unsupported,
                     path + ": required extension '" + shown + "' is not supported (" + why +
                         "); --ignore-required-extension " + shown + " renders the file without it");
  }
  // Used: declared or met. One warning per extension, in name order.
  std::map<std::string, std::string> used = extensionsFound(doc);
  for (const std::string& name : stringList(doc, "extensionsUsed")) used.emplace(name, "/extensionsUsed");
  for (const std::string& name : required) used.emplace(name, "/extensionsRequired");
  for (const auto& [name, where] : used) {
    const GltfExtension* e = findGltfExtension(name);
    const std::string shown = quoteForMessage(name);
    if (e == nullptr) {
      warnings->push_back(path + ": extension '" + shown + "' (" + quoteForMessage(where) +
                          ") is unknown to visbuf and ignored");
    } else if (e->support == S::Partial) {
      warnings->push_back(path + ": extension '" + shown + "' is read in part: " + std::string(e->effect) +
                          "; dropped: " + std::string(e->dropped));
    } else if (e->support == S::Dropped) {
      warnings->push_back(path + ": extension '" + shown + "' is not supported; dropped: " + std::string(e->dropped));
    }
  }
  return {};
}

}  // namespace visbuf
