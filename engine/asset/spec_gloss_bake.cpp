// KHR_materials_pbrSpecularGlossiness textures converted to metallic-roughness texels before the bake
// (contract in texture_bake.h, the conversion in scene/spec_gloss.h).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "visbuf/asset/texture_bake.h"
#include "visbuf/asset/texture_decode.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/scene/spec_gloss.h"

namespace visbuf {
namespace {

// Bilinear sample of a linear image at uv in [0,1]^2 (texel centres at (i + 0.5) / size, clamped at the edges).
glm::dvec4 sampleBilinear(const LinearImage& image, double u, double v) {
  const double x = std::clamp(u * image.width - 0.5, 0.0, double(image.width - 1));
  const double y = std::clamp(v * image.height - 0.5, 0.0, double(image.height - 1));
  const uint32_t x0 = uint32_t(x), y0 = uint32_t(y);
  const uint32_t x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const double fx = x - x0, fy = y - y0;
  auto at = [&](uint32_t px, uint32_t py) {
    const float* p = &image.rgba[(size_t(py) * image.width + px) * 4];
    return glm::dvec4(p[0], p[1], p[2], p[3]);
  };
  return glm::mix(glm::mix(at(x0, y0), at(x1, y0), fx), glm::mix(at(x0, y1), at(x1, y1), fx), fy);
}

// The image of a material slot decoded to linear light (RGB through the sRGB curve: both spec-gloss textures store
// sRGB colour; alpha is linear).
Result<LinearImage> decodeSlotImage(const ImportedScene& imported, const TextureRef& ref, uint64_t maxPixels) {
  const ImportedImage& image = imported.images[size_t(ref.image)];
  Result<std::vector<uint8_t>> file = image.path.empty() ? Result<std::vector<uint8_t>>(image.bytes) : readImageFile(image);
  if (!file) return makeError(file.error().code, imported.name + ": " + file.error().message);
  const std::string name =
      fmt::format("{}: image {} '{}'", quoteForMessage(imported.name), ref.image, quoteForMessage(image.name));
  return decodeImage(file->data(), file->size(), name, ColorSpace::Srgb, maxPixels);
}

// One converted image over `grid`'s texels: base colour (sRGB codes) or metallic-roughness (G roughness, B metallic).
ImportedImage convertedImage(const LinearImage& grid, const LinearImage* diffuse, const LinearImage* specular,
                             const Material::SpecGlossSource& f, bool baseColor, std::string name) {
  ImportedImage out;
  out.name = std::move(name);
  out.width = grid.width;
  out.height = grid.height;
  out.rgba8.resize(size_t(grid.width) * grid.height * 4);
  for (uint32_t y = 0; y < grid.height; ++y) {
    for (uint32_t x = 0; x < grid.width; ++x) {
      const double u = (x + 0.5) / grid.width, v = (y + 0.5) / grid.height;
      const glm::dvec4 d = glm::dvec4(f.diffuse) * (diffuse ? sampleBilinear(*diffuse, u, v) : glm::dvec4(1.0));
      const glm::dvec4 s = specular ? sampleBilinear(*specular, u, v) : glm::dvec4(1.0);
      const MetalRough mr = specGlossToMetalRough(d, glm::dvec3(f.specular) * glm::dvec3(s), double(f.glossiness) * s.a);
      uint8_t* p = &out.rgba8[(size_t(y) * grid.width + x) * 4];
      if (baseColor) {
        for (int c = 0; c < 3; ++c) p[c] = encodeSrgb8(float(mr.baseColor[c]));
        p[3] = uint8_t(std::lround(std::clamp(mr.baseColor.a, 0.0, 1.0) * 255.0));
      } else {
        p[0] = 255;
        p[1] = uint8_t(std::lround(mr.roughness * 255.0));
        p[2] = uint8_t(std::lround(mr.metallic * 255.0));
        p[3] = 255;
      }
    }
  }
  return out;
}

}  // namespace

Status convertSpecGlossTextures(const ImportedScene& imported, const TextureBakeOptions& options, Scene* scene,
                                std::vector<ImportedImage>* derived, std::vector<std::string>* notes) {
  for (Material& m : scene->materials) {
    if (!m.specGloss) continue;
    const Material::SpecGlossSource f = *m.specGloss;
    TextureRef& diffuseRef = m.baseColorTexture;
    TextureRef& specularRef = m.metallicRoughnessTexture;
    LinearImage diffuse, specular;
    for (auto [ref, image] : {std::pair{&diffuseRef, &diffuse}, std::pair{&specularRef, &specular}}) {
      if (ref->image < 0) continue;
      if (size_t(ref->image) >= imported.images.size())
        return makeError(ErrorCode::MalformedInput, fmt::format("material '{}': image {} does not exist ({} images)",
                                                                m.name, ref->image, imported.images.size()));
      Result<LinearImage> decoded = decodeSlotImage(imported, *ref, options.maxImagePixels);
      if (!decoded) return decoded.error();
      *image = std::move(decoded.value());
    }
    const bool hasDiffuse = diffuseRef.image >= 0, hasSpecular = specularRef.image >= 0;
    // Texel for texel only where both textures map the surface alike; else each converts against the other's factor.
    const bool joint = hasDiffuse && hasSpecular && diffuseRef.texCoord == specularRef.texCoord &&
                       diffuseRef.transform == specularRef.transform;
    if (hasDiffuse && hasSpecular && !joint && notes)
      notes->push_back(fmt::format("material '{}': {} textures use different texture coordinates: each converted "
                                   "against the other's factor",
                                   quoteForMessage(m.name), "KHR_materials_pbrSpecularGlossiness"));
    const LinearImage* d = hasDiffuse ? &diffuse : nullptr;
    const LinearImage* s = hasSpecular ? &specular : nullptr;
    const TextureRef baseRef = hasDiffuse ? diffuseRef : specularRef;
    const TextureRef mrRef = hasSpecular ? specularRef : diffuseRef;
    const size_t first = imported.images.size() + derived->size();
    // (each image over its own texture's texels; the other texture is sampled at the same uv where they share it)
    derived->push_back(convertedImage(hasDiffuse ? diffuse : specular, d, joint || !hasDiffuse ? s : nullptr, f, true,
                                      m.name + " base colour (from specular-glossiness)"));
    derived->push_back(convertedImage(hasSpecular ? specular : diffuse, joint || !hasSpecular ? d : nullptr, s, f, false,
                                      m.name + " metallic-roughness (from specular-glossiness)"));
    diffuseRef = baseRef;
    diffuseRef.image = int32_t(first);
    specularRef = mrRef;
    specularRef.image = int32_t(first + 1);
    // The factors are in the texels now (the factors' own conversion was only the unbaked stand-in).
    m.baseColor = glm::vec4(1.0f);
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.specGloss.reset();
  }
  return {};
}

}  // namespace visbuf
