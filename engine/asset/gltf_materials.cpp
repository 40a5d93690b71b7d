// glTF materials, texture references, samplers, KHR_texture_transform and the images they use, for
// importGltfScene (contract in gltf_import.h). Nothing here reads pixels: images are collected as encoded bytes
// or file paths and decoded by texture_bake.cpp.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "visbuf/asset/gltf_detail.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/scene/spec_gloss.h"

namespace visbuf::gltf_detail {
namespace {

constexpr const char* kTextureTransformExt = "KHR_texture_transform";
constexpr const char* kBasisuExt = "KHR_texture_basisu";
constexpr const char* kEmissiveStrengthExt = "KHR_materials_emissive_strength";
constexpr const char* kUnlitExt = "KHR_materials_unlit";
constexpr const char* kClearcoatExt = "KHR_materials_clearcoat";
constexpr const char* kSpecGlossExt = "KHR_materials_pbrSpecularGlossiness";

bool allFinite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// Reads `n` factors into out[0..n), clamped to [0,1] with a warning; a wrong count or NaN/Inf is an error.
Status readUnitFactors(const std::vector<double>& f, size_t n, const char* field, const std::string& where,
                       const WarnFn& warn, float* out) {
  if (f.size() != n) return malformed(where + ": " + field + " must have " + str(uint64_t{n}) + " element(s)");
  if (!allFinite(f)) return malformed(where + ": non-finite " + field);
  bool clamped = false;
  for (size_t c = 0; c < n; ++c) {
    const double v = std::clamp(f[c], 0.0, 1.0);
    clamped |= v != f[c];
    out[c] = static_cast<float>(v);
  }
  if (clamped) warn(where + ": " + field + " outside [0,1] clamped");
  return {};
}

WrapMode wrapMode(int gl, const std::string& where, const WarnFn& warn) {
  switch (gl) {
    case TINYGLTF_TEXTURE_WRAP_REPEAT: return WrapMode::Repeat;
    case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return WrapMode::ClampToEdge;
    case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return WrapMode::MirroredRepeat;
  }
  warn(where + ": unknown wrap mode " + str(gl) + " treated as REPEAT");
  return WrapMode::Repeat;
}

// glTF sampler -> SamplerState. Undefined filters (-1) are trilinear; unknown values warn and use it too.
Result<SamplerState> samplerState(const tinygltf::Model& model, int index, const std::string& where,
                                  const WarnFn& warn) {
  SamplerState s;
  if (index < 0) return s;
  if (static_cast<size_t>(index) >= model.samplers.size())
    return malformed(where + ": sampler " + str(index) + " does not exist");
  const tinygltf::Sampler& gs = model.samplers[static_cast<size_t>(index)];
  const std::string sw = where + ": sampler " + str(index);
  s.wrapS = wrapMode(gs.wrapS, sw, warn);
  s.wrapT = wrapMode(gs.wrapT, sw, warn);
  if (gs.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST) {
    s.magFilter = TextureFilter::Nearest;
  } else if (gs.magFilter != TINYGLTF_TEXTURE_FILTER_LINEAR && gs.magFilter != -1) {
    warn(sw + ": unknown magFilter " + str(gs.magFilter) + " treated as LINEAR");
  }
  using F = TextureFilter;
  using M = MipFilter;
  switch (gs.minFilter) {
    case TINYGLTF_TEXTURE_FILTER_NEAREST: s.minFilter = F::Nearest, s.mipFilter = M::None; break;
    case TINYGLTF_TEXTURE_FILTER_LINEAR: s.minFilter = F::Linear, s.mipFilter = M::None; break;
    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST: s.minFilter = F::Nearest, s.mipFilter = M::Nearest; break;
    case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_NEAREST: s.minFilter = F::Linear, s.mipFilter = M::Nearest; break;
    case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR: s.minFilter = F::Nearest, s.mipFilter = M::Linear; break;
    case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR:
    case -1: break;
    default: warn(sw + ": unknown minFilter " + str(gs.minFilter) + " treated as LINEAR_MIPMAP_LINEAR");
  }
  return s;
}

// Reads a JSON array of `n` numbers from an extension object; false when absent or malformed.
bool numbers(const tinygltf::Value& object, const char* key, size_t n, double* out) {
  if (!object.Has(key)) return false;
  const tinygltf::Value& v = object.Get(key);
  if (!v.IsArray() || v.ArrayLen() != n) return false;
  for (size_t i = 0; i < n; ++i) {
    if (!v.Get(static_cast<int>(i)).IsNumber()) return false;
    out[i] = v.Get(static_cast<int>(i)).GetNumberAsDouble();
  }
  return true;
}

// Applies KHR_texture_transform (offset, rotation, scale, texCoord) to `ref`. Fields of the wrong shape are
// ignored with a warning; NaN/Inf is an error.
Status applyTextureTransform(const tinygltf::Value& ext, const std::string& where, const WarnFn& warn,
                             TextureRef* ref) {
  const std::string w = where + " " + kTextureTransformExt;
  if (!ext.IsObject()) return malformed(w + ": not an object");
  double offset[2] = {0.0, 0.0}, scale[2] = {1.0, 1.0}, rotation = 0.0;
  for (auto [key, n, dst] : {std::tuple{"offset", size_t{2}, offset}, std::tuple{"scale", size_t{2}, scale}}) {
    if (ext.Has(key) && !numbers(ext, key, n, dst)) warn(w + ": '" + key + "' is not 2 numbers; ignored");
  }
  if (ext.Has("rotation")) {
    if (ext.Get("rotation").IsNumber()) {
      rotation = ext.Get("rotation").GetNumberAsDouble();
    } else {
      warn(w + ": 'rotation' is not a number; ignored");
    }
  }
  if (!std::isfinite(offset[0] + offset[1] + scale[0] + scale[1] + rotation))
    return malformed(w + ": non-finite offset, rotation or scale");
  if (ext.Has("texCoord")) {
    const tinygltf::Value& t = ext.Get("texCoord");
    if (t.IsInt() && t.Get<int>() >= 0) {
      ref->texCoord = static_cast<uint32_t>(t.Get<int>());
    } else {
      warn(w + ": 'texCoord' is not an index; ignored");
    }
  }
  // The extension's matrix T * R * S, with R = [cos sin; -sin cos] (rotation counter-clockwise in uv space).
  const double c = std::cos(rotation), s = std::sin(rotation);
  ref->transform = glm::mat3x2(glm::dmat3x2(c * scale[0], -s * scale[0], s * scale[1], c * scale[1],
                                            offset[0], offset[1]));
  return {};
}

template <typename Info>
Result<TextureRef> textureRef(const tinygltf::Model& model, const Info& info, const std::string& where,
                              const WarnFn& warn) {
  TextureRef ref;
  if (info.index < 0) return ref;
  if (static_cast<size_t>(info.index) >= model.textures.size())
    return malformed(where + ": texture " + str(info.index) + " does not exist");
  const tinygltf::Texture& texture = model.textures[static_cast<size_t>(info.index)];
  ref.texture = info.index;
  ref.texCoord = info.texCoord > 0 ? static_cast<uint32_t>(info.texCoord) : 0;
  // KHR_texture_basisu keeps its KTX2 image in the extension and the optional plain `source` as the fallback
  // for readers without a Basis Universal transcoder (this one): the fallback is what a texture offers us.
  const bool basisu = texture.extensions.count(kBasisuExt) != 0;
  if (texture.source >= 0 && static_cast<size_t>(texture.source) < model.images.size()) {
    ref.image = texture.source;
    ref.uri = model.images[static_cast<size_t>(texture.source)].uri;
  } else if (basisu) {
    warn(where + ": texture " + str(info.index) + named(texture.name) + " has only a " + kBasisuExt +
         " (KTX2 / Basis Universal) image, which is not supported, and no fallback `source`; texture dropped");
  } else {
    warn(where + ": texture " + str(info.index) + " has no usable image source");
  }
  auto sampler = samplerState(model, texture.sampler, where, warn);
  if (!sampler) return sampler.error();
  ref.sampler = *sampler;
  if (auto it = info.extensions.find(kTextureTransformExt); it != info.extensions.end()) {
    if (Status s = applyTextureTransform(it->second, where, warn, &ref); !s) return s.error();
  }
  if (ref.texCoord > 1) {
    warn(where + ": TEXCOORD_" + str(uint64_t{ref.texCoord}) + " is not imported; TEXCOORD_0 is used");
    ref.texCoord = 0;
  }
  return ref;
}

// Reads the extension factor(s) `key` of extension object `ext` (n numbers: one, or an array of n) into out[0..n)
// when present. The schema check (gltf_validate.cpp) has refused wrong types and values outside [low, high]
// already; this refuses them again for callers that skip it.
Status extensionFactors(const tinygltf::Value& ext, const char* key, size_t n, double low, double high,
                        const std::string& where, float* out) {
  if (!ext.Has(key)) return {};
  const tinygltf::Value& v = ext.Get(key);
  for (size_t i = 0; i < n; ++i) {
    const tinygltf::Value& x = n == 1 ? v : v.Get(static_cast<int>(i));
    const double value = x.IsNumber() ? x.GetNumberAsDouble() : NAN;
    if ((n > 1 && (!v.IsArray() || v.ArrayLen() != n)) || !(value >= low && value <= high))
      return malformed(where + ": '" + key + "' must be " + (n > 1 ? str(uint64_t{n}) + " numbers" : "a number") +
                       " in [" + fmt::format("{}, {}", low, high) + "]");
    out[i] = static_cast<float>(value);
  }
  return {};
}

// An extension's textureInfo object `key` (absent: index -1) as tinygltf's struct, for textureRef. Fields of the
// wrong type were refused by the schema check; here they are left at their defaults.
tinygltf::NormalTextureInfo extensionTextureInfo(const tinygltf::Value& ext, const char* key) {
  tinygltf::NormalTextureInfo info;
  if (!ext.Has(key) || !ext.Get(key).IsObject()) return info;
  const tinygltf::Value& v = ext.Get(key);
  if (v.Get("index").IsInt()) info.index = v.Get("index").Get<int>();
  if (v.Get("texCoord").IsInt()) info.texCoord = v.Get("texCoord").Get<int>();
  if (v.Get("scale").IsNumber()) info.scale = v.Get("scale").GetNumberAsDouble();
  const tinygltf::Value& extensions = v.Get("extensions");
  if (extensions.IsObject())
    for (const std::string& name : extensions.Keys()) info.extensions[name] = extensions.Get(name);
  return info;
}

// KHR_materials_unlit, KHR_materials_clearcoat and KHR_materials_pbrSpecularGlossiness (scene.h Material).
Status convertExtensions(const tinygltf::Model& model, const tinygltf::Material& gm, const std::string& where,
                         const WarnFn& warn, Material* m) {
  if (auto it = gm.extensions.find(kUnlitExt); it != gm.extensions.end()) {
    if (!it->second.IsObject()) return malformed(where + ": " + kUnlitExt + " is not an object");
    m->unlit = true;
  }
  if (auto it = gm.extensions.find(kSpecGlossExt); it != gm.extensions.end()) {
    const tinygltf::Value& ext = it->second;
    const std::string w = where + " " + kSpecGlossExt;
    if (!ext.IsObject()) return malformed(w + ": not an object");
    Material::SpecGlossSource sg;
    if (Status s = extensionFactors(ext, "diffuseFactor", 4, 0.0, 1.0, w, &sg.diffuse[0]); !s) return s;
    if (Status s = extensionFactors(ext, "specularFactor", 3, 0.0, 1.0, w, &sg.specular[0]); !s) return s;
    if (Status s = extensionFactors(ext, "glossinessFactor", 1, 0.0, 1.0, w, &sg.glossiness); !s) return s;
    // The extension replaces the metallic-roughness block (a file may carry both for readers without it).
    auto diffuse = textureRef(model, extensionTextureInfo(ext, "diffuseTexture"), w + " diffuseTexture", warn);
    if (!diffuse) return diffuse.error();
    auto specular =
        textureRef(model, extensionTextureInfo(ext, "specularGlossinessTexture"), w + " specularGlossinessTexture", warn);
    if (!specular) return specular.error();
    m->baseColorTexture = std::move(diffuse.value());
    m->metallicRoughnessTexture = std::move(specular.value());
    const MetalRough mr = specGlossToMetalRough(glm::dvec4(sg.diffuse), glm::dvec3(sg.specular), sg.glossiness);
    m->baseColor = glm::vec4(mr.baseColor);
    m->metallic = static_cast<float>(mr.metallic);
    m->roughness = static_cast<float>(mr.roughness);
    if (m->baseColorTexture.texture >= 0 || m->metallicRoughnessTexture.texture >= 0) m->specGloss = sg;
  }
  if (auto it = gm.extensions.find(kClearcoatExt); it != gm.extensions.end()) {
    const tinygltf::Value& ext = it->second;
    const std::string w = where + " " + kClearcoatExt;
    if (!ext.IsObject()) return malformed(w + ": not an object");
    if (Status s = extensionFactors(ext, "clearcoatFactor", 1, 0.0, 1.0, w, &m->clearcoat); !s) return s;
    if (Status s = extensionFactors(ext, "clearcoatRoughnessFactor", 1, 0.0, 1.0, w, &m->clearcoatRoughness); !s)
      return s;
    struct CoatSlot {
      const char* key;
      TextureRef* out;
    };
    for (const CoatSlot& slot : {CoatSlot{"clearcoatTexture", &m->clearcoatTexture},
                                 CoatSlot{"clearcoatRoughnessTexture", &m->clearcoatRoughnessTexture},
                                 CoatSlot{"clearcoatNormalTexture", &m->clearcoatNormalTexture}}) {
      const tinygltf::NormalTextureInfo info = extensionTextureInfo(ext, slot.key);
      auto ref = textureRef(model, info, w + " " + slot.key, warn);
      if (!ref) return ref.error();
      *slot.out = std::move(ref.value());
      if (slot.out == &m->clearcoatNormalTexture) {
        if (!std::isfinite(info.scale)) return malformed(w + ": non-finite clearcoatNormalTexture.scale");
        m->clearcoatNormalScale = static_cast<float>(info.scale);
      }
    }
  }
  return {};
}

// Fills the metallic-roughness factors, normal/occlusion/emissive parameters and every texture reference.
Status convertPbr(const tinygltf::Model& model, const tinygltf::Material& gm, const std::string& where,
                  const WarnFn& warn, Material* m) {
  const tinygltf::PbrMetallicRoughness& pbr = gm.pbrMetallicRoughness;
  if (Status s = readUnitFactors(pbr.baseColorFactor, 4, "baseColorFactor", where, warn, &m->baseColor[0]); !s)
    return s;
  if (Status s = readUnitFactors({pbr.metallicFactor}, 1, "metallicFactor", where, warn, &m->metallic); !s) return s;
  if (Status s = readUnitFactors({pbr.roughnessFactor}, 1, "roughnessFactor", where, warn, &m->roughness); !s)
    return s;
  const std::vector<double> emissive = gm.emissiveFactor.empty() ? std::vector<double>(3, 0.0) : gm.emissiveFactor;
  if (Status s = readUnitFactors(emissive, 3, "emissiveFactor", where, warn, &m->emissive[0]); !s) return s;
  if (Status s = readUnitFactors({gm.occlusionTexture.strength}, 1, "occlusionTexture.strength", where, warn,
                                 &m->occlusionStrength);
      !s)
    return s;
  if (!std::isfinite(gm.normalTexture.scale)) return malformed(where + ": non-finite normalTexture.scale");
  m->normalScale = static_cast<float>(gm.normalTexture.scale);
  if (auto it = gm.extensions.find(kEmissiveStrengthExt); it != gm.extensions.end()) {
    if (Status s = extensionFactors(it->second, "emissiveStrength", 1, 0.0, HUGE_VAL, where, &m->emissiveStrength); !s)
      return s;
  }
  struct Slot {
    const char* name;
    Result<TextureRef> ref;
    TextureRef* out;
  };
  Slot slots[] = {
      {"baseColorTexture", textureRef(model, pbr.baseColorTexture, where + " baseColorTexture", warn),
       &m->baseColorTexture},
      {"metallicRoughnessTexture",
       textureRef(model, pbr.metallicRoughnessTexture, where + " metallicRoughnessTexture", warn),
       &m->metallicRoughnessTexture},
      {"normalTexture", textureRef(model, gm.normalTexture, where + " normalTexture", warn), &m->normalTexture},
      {"occlusionTexture", textureRef(model, gm.occlusionTexture, where + " occlusionTexture", warn),
       &m->occlusionTexture},
      {"emissiveTexture", textureRef(model, gm.emissiveTexture, where + " emissiveTexture", warn),
       &m->emissiveTexture},
  };
  for (Slot& slot : slots) {
    if (!slot.ref) return slot.ref.error();
    *slot.out = std::move(slot.ref.value());
  }
  return {};
}

}  // namespace

Status importMaterials(const tinygltf::Model& model, const std::string& path, const WarnFn& warn,
                       std::vector<Material>* out) {
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const tinygltf::Material& gm = model.materials[i];
    const std::string where = path + ": material " + str(uint64_t{i}) + named(gm.name);
    Material m;
    m.name = gm.name.empty() ? "material" + str(uint64_t{i}) : gm.name;
    if (Status s = convertPbr(model, gm, where, warn, &m); !s) return s;
    if (Status s = convertExtensions(model, gm, where, warn, &m); !s) return s;
    if (gm.alphaMode == "MASK") {
      m.alphaMode = AlphaMode::Mask;
    } else if (gm.alphaMode == "BLEND") {
      m.alphaMode = AlphaMode::Blend;
    } else {
      if (gm.alphaMode != "OPAQUE" && !gm.alphaMode.empty())
        warn(where + ": unknown alphaMode '" + gm.alphaMode + "' treated as OPAQUE");
      m.alphaMode = AlphaMode::Opaque;
    }
    if (!std::isfinite(gm.alphaCutoff)) return malformed(where + ": non-finite alphaCutoff");
    m.alphaCutoff = static_cast<float>(gm.alphaCutoff);
    m.doubleSided = gm.doubleSided;
    out->push_back(std::move(m));
  }
  return {};
}

Status collectImages(const tinygltf::Model& model, const std::string& path, const LoadedReferences& references,
                     std::vector<ImportedImage>* out) {
  for (size_t i = 0; i < model.images.size(); ++i) {
    const tinygltf::Image& gi = model.images[i];
    const std::string where = path + ": image " + str(uint64_t{i}) + named(gi.name);
    ImportedImage im;
    im.name = !gi.name.empty() ? gi.name : !gi.uri.empty() ? gi.uri : "image " + str(uint64_t{i});
    im.uri = gi.uri;
    im.mimeType = gi.mimeType;
    if (gi.bufferView >= 0) {
      if (static_cast<size_t>(gi.bufferView) >= model.bufferViews.size())
        return malformed(where + ": bufferView " + str(gi.bufferView) + " does not exist");
      const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(gi.bufferView)];
      if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size())
        return malformed(where + ": bufferView " + str(gi.bufferView) + " refers to missing buffer");
      const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(view.buffer)].data;
      if (!rangeFits(view.byteOffset, view.byteLength, data.size()))
        return malformed(where + ": bufferView " + str(gi.bufferView) + " runs past the end of its buffer");
      const auto first = data.begin() + static_cast<std::ptrdiff_t>(view.byteOffset);
      im.bytes.assign(first, first + static_cast<std::ptrdiff_t>(view.byteLength));
    } else if (!gi.uri.empty() && i < references.imagePaths.size() && !references.imagePaths[i].empty()) {
      im.path = references.imagePaths[i];  // resolved and checked by the URI rule (uri_resolver.h)
    } else {
      im.bytes = gi.image;  // a data: URI, decoded from base64 by tinygltf and kept by loadModel
    }
    out->push_back(std::move(im));
  }
  return {};
}

}  // namespace visbuf::gltf_detail
