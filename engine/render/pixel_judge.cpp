#include "visbuf/render/pixel_judge.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "visbuf/render/brdf_reference.h"
#include "visbuf/render/texture_reference.h"

namespace visbuf {

PixelRay pixelRay(const FrameMath& math, double px, double py) {
  const double nx = px / math.width * 2.0 - 1.0, ny = py / math.height * 2.0 - 1.0;
  const glm::dmat3 toWorld = glm::transpose(glm::dmat3(math.view));  // the view is a pure rotation
  const glm::dvec3 onPlane(nx / math.proj[0][0], ny / math.proj[1][1], 0.0);
  if (math.orthographic) return {toWorld * onPlane, toWorld * glm::dvec3(0.0, 0.0, -1.0)};
  return {glm::dvec3(0.0), toWorld * (onPlane + glm::dvec3(0.0, 0.0, -1.0))};
}

std::optional<std::pair<double, glm::dvec3>> intersectTriangle(const glm::dvec3 v[3], const PixelRay& ray) {
  const glm::dvec3& dir = ray.dir;
  const glm::dvec3 e1 = v[1] - v[0], e2 = v[2] - v[0];
  const glm::dvec3 pvec = glm::cross(dir, e2);
  const double det = glm::dot(e1, pvec);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const glm::dvec3 tvec = ray.origin - v[0];
  const double u = glm::dot(tvec, pvec) / det;
  const glm::dvec3 qvec = glm::cross(tvec, e1);
  const double w = glm::dot(dir, qvec) / det;
  const double t = glm::dot(e2, qvec) / det;
  return std::make_pair(t, glm::dvec3(1.0 - u - w, u, w));
}

namespace {

// A triangle one path claims at a pixel, and what the pixel's ray says about it.
struct Claim {
  uint32_t object = 0, triangle = 0;  // object index (ID - 1), triangle in the drawn LOD
  uint32_t lod = 0;
  glm::dvec3 v[3];                    // camera-relative world positions
  uint32_t index[3] = {0, 0, 0};      // mesh vertex indices
  bool hit = false;                   // the ray is not parallel to the triangle
  double t = 0.0;
  glm::dvec3 lambda{0.0};
  bool inside() const { return hit && t > 0.0 && lambda.x >= 0.0 && lambda.y >= 0.0 && lambda.z >= 0.0; }
  double minLambda() const { return hit ? std::min({lambda.x, lambda.y, lambda.z}) : -INFINITY; }
};

// The per-object LOD a frame drew (readDraws), else 0.
std::vector<uint32_t> drawnLods(const Scene& scene, const FrameResult& f) {
  std::vector<uint32_t> lods(scene.objects.size(), 0u);
  for (size_t i = 0; i < f.drawnObjects.size() && i < f.drawnLods.size(); ++i)
    if (f.drawnObjects[i] < lods.size()) lods[f.drawnObjects[i]] = f.drawnLods[i];
  return lods;
}

// Normal to world space: the cofactor matrix of the linear part, times sign(det) (the inverse transpose up to a
// positive scale, which the normalisation removes).
glm::dvec3 normalToWorld(const glm::dmat3& m, const glm::dvec3& n) {
  const glm::dmat3 cofactor = glm::transpose(glm::inverse(m)) * glm::determinant(m);
  return (glm::determinant(m) < 0.0 ? -1.0 : 1.0) * (cofactor * n);
}

glm::dvec4 unpackUnorm4x8(uint32_t c) {
  return glm::dvec4(c & 0xffu, (c >> 8) & 0xffu, (c >> 16) & 0xffu, c >> 24) / 255.0;
}

// What the paths interpolate at the hit (material.glsl's SurfaceInputs), in double.
struct Interpolated {
  glm::dvec3 normal{0.0};   // world, not normalised
  glm::dvec4 tangent{0.0};  // world xyz, w: bitangent sign; w == 0: none
  glm::dvec3 dpdx{0.0}, dpdy{0.0};
  glm::dvec2 uv[2] = {glm::dvec2(0.0), glm::dvec2(0.0)}, duvdx[2] = {glm::dvec2(0.0), glm::dvec2(0.0)},
             duvdy[2] = {glm::dvec2(0.0), glm::dvec2(0.0)};
  glm::dvec4 color{0.0};
};

// material.glsl's tangentFrame: the mesh's tangent, else dP/du from the position and uv derivatives.
bool tangentFrame(const Interpolated& in, const glm::dvec3& n, int set, glm::dvec3& t, glm::dvec3& b) {
  if (in.tangent.w != 0.0) {
    t = glm::dvec3(in.tangent) - n * glm::dot(n, glm::dvec3(in.tangent));
    if (glm::dot(t, t) <= 0.0) return false;
    t = glm::normalize(t);
    b = glm::cross(n, t) * (in.tangent.w < 0.0 ? -1.0 : 1.0);
    return true;
  }
  const glm::dvec2 dx = in.duvdx[set], dy = in.duvdy[set];
  const double det = dx.x * dy.y - dx.y * dy.x;
  if (std::abs(det) <= 1e-20) return false;
  const glm::dvec3 dpdu = (dy.y * in.dpdx - dx.y * in.dpdy) / det;
  const glm::dvec3 dpdv = (dx.x * in.dpdy - dy.x * in.dpdx) / det;
  t = dpdu - n * glm::dot(n, dpdu);
  if (glm::dot(t, t) <= 0.0) return false;
  t = glm::normalize(t);
  b = glm::cross(n, t) * (glm::dot(glm::cross(n, t), dpdv) < 0.0 ? -1.0 : 1.0);
  return true;
}

// The exact colour of a claimed triangle at the ray's hit through pixel position (cx, cy): the attributes
// interpolated with the hit's barycentrics (their screen derivatives from rays 1e-3 pixel apart, for texture
// filtering and derived tangents), material.glsl's evaluateMaterial, then lighting.glsl's shadeSurface through
// shadeReference.
glm::dvec3 exactColor(const Scene& scene, const Camera& camera, const FrameMath& math, TextureReference& textures,
                      const glm::dmat4& transform, const Claim& c, double cx, double cy) {
  const Object& o = scene.objects[c.object];
  const Mesh& mesh = scene.meshes[o.mesh];
  const Material& m = scene.materials[o.material];
  const auto slots = textureSlots(m);
  bool textured = false;
  for (const TextureRef* t : slots) textured |= t->baked >= 0 && size_t(t->baked) < scene.textures.size();
  glm::dvec3 ddx(0.0), ddy(0.0);
  if (textured) {
    const double h = 1e-3;  // pixels; lambda is smooth at this scale, the difference quotient exact to ~1e-9
    auto lambdaAt = [&](double px, double py) {
      auto s = intersectTriangle(c.v, pixelRay(math, px, py));
      return s ? s->second : glm::dvec3(NAN);
    };
    ddx = (lambdaAt(cx + h, cy) - lambdaAt(cx - h, cy)) / (2.0 * h);
    ddy = (lambdaAt(cx, cy + h) - lambdaAt(cx, cy - h)) / (2.0 * h);
  }
  const glm::dmat3 linear(transform);
  Interpolated in;
  glm::dvec3 tangent(0.0);
  for (int k = 0; k < 3; ++k) {
    const uint32_t i = c.index[k];
    const gpu::Vertex& v = mesh.vertices[i];
    in.normal += c.lambda[k] * glm::dvec3(octDecode(v.normal));
    in.color += c.lambda[k] * unpackUnorm4x8(v.color);
    in.dpdx += ddx[k] * c.v[k];
    in.dpdy += ddy[k] * c.v[k];
    const glm::dvec2 uv[2] = {glm::dvec2(v.u, v.v), mesh.uvs1.empty() ? glm::dvec2(0.0) : glm::dvec2(mesh.uvs1[i])};
    for (int set = 0; set < 2; ++set) {
      in.uv[set] += c.lambda[k] * uv[set];
      in.duvdx[set] += ddx[k] * uv[set];
      in.duvdy[set] += ddy[k] * uv[set];
    }
    // The GPU's tangents are octahedral-encoded (gpu_scene.cpp): the same quantisation here.
    if (!mesh.tangents.empty() && mesh.tangents[i].w != 0.0f)
      tangent += c.lambda[k] * glm::dvec3(octDecode(octEncode(glm::normalize(glm::vec3(mesh.tangents[i])))));
    else
      tangent += c.lambda[k] * glm::dvec3(octDecode(0u));
  }
  if (!mesh.tangents.empty() && mesh.tangents[c.index[0]].w != 0.0f)  // (the first vertex's sign, as the shader)
    in.tangent = glm::dvec4(linear * tangent, mesh.tangents[c.index[0]].w < 0.0f ? -1.0 : 1.0);
  glm::dvec4 texel[kTextureSlotCount];
  for (size_t k = 0; k < kTextureSlotCount; ++k) {
    const int set = slots[k]->texCoord == 1 ? 1 : 0;
    texel[k] = textures.sample(*slots[k], in.uv[set], in.duvdx[set], in.duvdy[set]);
  }
  SurfaceReference s;
  const PixelRay ray = pixelRay(math, cx, cy);
  s.position = ray.at(c.t);
  if (math.orthographic) s.towardsEye = -ray.dir;
  glm::dvec3 n = glm::normalize(normalToWorld(linear, in.normal));
  // Front faces are counter-clockwise on screen: the triangle's geometric normal faces the ray's origin (the
  // camera; orthographic: the pixel's point on the camera plane), the winding reversed for a mirroring transform
  // (shade.comp.glsl's frontFacing). Back faces of double-sided materials flip the whole tangent frame.
  const bool facing = glm::dot(glm::cross(c.v[1] - c.v[0], c.v[2] - c.v[0]), c.v[0] - ray.origin) < 0.0;
  const bool frontFacing = facing != (glm::determinant(linear) < 0.0);
  const double side = m.doubleSided && !frontFacing ? -1.0 : 1.0;
  // material.glsl's mappedNormal: a normal-mapped slot's unit normal (side * n without its texture).
  auto mapped = [&](const TextureRef& map, const glm::dvec4& sample, double scale) {
    glm::dvec3 t, b;
    if (map.baked < 0 || size_t(map.baked) >= scene.textures.size() || !tangentFrame(in, n, map.texCoord == 1 ? 1 : 0, t, b))
      return side * n;
    glm::dvec3 tn = glm::dvec3(sample) * 2.0 - 1.0;
    const Texture& tex = scene.textures[size_t(map.baked)];
    if (scene.textureClasses[tex.sizeClass].format == TextureFormat::Bc5)  // x, y of a unit vector: z rebuilt
      tn.z = std::sqrt(std::max(0.0, 1.0 - tn.x * tn.x - tn.y * tn.y));
    tn.x *= scale;
    tn.y *= scale;
    const glm::dvec3 v = side * (t * tn.x + b * tn.y + n * tn.z);
    return glm::dot(v, v) > 0.0 ? glm::normalize(v) : side * n;
  };
  s.baseColor = glm::dvec3(glm::dvec4(m.baseColor) * in.color * texel[TEXTURE_SLOT_BASE_COLOR]);
  s.normal = side * n;
  if (m.unlit) {
    s.unlit = true;
    return shadeReference(s, scene, camera.position);
  }
  s.normal = mapped(m.normalTexture, texel[TEXTURE_SLOT_NORMAL], double(m.normalScale));
  s.metallic = std::clamp(double(m.metallic) * texel[TEXTURE_SLOT_METALLIC_ROUGHNESS].b, 0.0, 1.0);
  s.roughness = std::clamp(double(m.roughness) * texel[TEXTURE_SLOT_METALLIC_ROUGHNESS].g, 0.0, 1.0);
  const TextureRef& occlusion = m.occlusionTexture;
  if (occlusion.baked >= 0 && size_t(occlusion.baked) < scene.textures.size())
    s.occlusion = 1.0 + double(m.occlusionStrength) * (texel[TEXTURE_SLOT_OCCLUSION].r - 1.0);
  s.emissive = glm::dvec3(m.emissive) * double(m.emissiveStrength) * glm::dvec3(texel[TEXTURE_SLOT_EMISSIVE]);
  if (m.clearcoat > 0.0f) {
    s.clearcoat = std::clamp(double(m.clearcoat) * texel[TEXTURE_SLOT_CLEARCOAT].r, 0.0, 1.0);
    s.clearcoatRoughness = std::clamp(double(m.clearcoatRoughness) * texel[TEXTURE_SLOT_CLEARCOAT_ROUGHNESS].g, 0.0, 1.0);
    s.clearcoatNormal = mapped(m.clearcoatNormalTexture, texel[TEXTURE_SLOT_CLEARCOAT_NORMAL], double(m.clearcoatNormalScale));
  }
  return shadeReference(s, scene, camera.position);
}

// The spacing of rgba16f values at v (11 significant bits; the subnormal spacing below 2^-14): how far a correctly
// converted output may lie from v. Vulkan lets a device convert to 16-bit floats by rounding to nearest or towards
// zero (lavapipe rounds towards zero: 99.8% of its channels lie below the exact colour), so a whole spacing.
double halfFloatSpacing(double v) {
  const int e = std::max(int(std::floor(std::log2(std::max(std::abs(v), 1e-300)))), -14);
  return std::ldexp(1.0, e - 10);
}

void addError(PathAccuracy& a, double& sumAbs, double& sumSq, const float* path, const glm::dvec3& exact,
              double& pixelError) {
  pixelError = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::abs(double(path[k]) - exact[k]);
    pixelError = std::isnan(d) ? INFINITY : std::max(pixelError, d);
    a.maxBeyondRounding = std::isnan(d) ? INFINITY : std::max(a.maxBeyondRounding, d - halfFloatSpacing(exact[k]));
    sumAbs += d;
    sumSq += d * d;
  }
  a.maxAbs = std::max(a.maxAbs, pixelError);
  a.over8Bit += pixelError > 1.0 / 255.0;
}

float heat(double error) { return float(std::clamp((std::log10(std::max(error, 1e-30)) + 5.0) / 4.0, 0.0, 1.0)); }

// The claim of a path that shows triangle `triangle` of object ID `id` (object + 1) at LOD `lod` at pixel (x, y),
// with the hit of the ray `dir` on it.
Result<Claim> makeClaim(const Scene& scene, const std::vector<glm::dmat4>& transforms, const Camera& camera,
                        uint32_t id, uint32_t triangle, uint32_t lod, uint32_t x, uint32_t y, const PixelRay& dir) {
  if (id > scene.objects.size())
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("judge: pixel ({}, {}) shows object ID {} of {}", x, y, id - 1, scene.objects.size()));
  Claim c;
  c.object = id - 1;
  c.triangle = triangle;
  c.lod = lod;
  const Mesh& mesh = scene.meshes[scene.objects[c.object].mesh];
  if (c.lod >= mesh.lods.size() || c.triangle >= mesh.triangleCount(c.lod))
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("judge: pixel ({}, {}) shows triangle {} of LOD {} of object {}: it has {}", x, y,
                                 c.triangle, c.lod, c.object, c.lod < mesh.lods.size() ? mesh.triangleCount(c.lod) : 0u));
  for (int k = 0; k < 3; ++k) {
    c.index[k] = mesh.indices[mesh.lods[c.lod].firstIndex + 3 * c.triangle + uint32_t(k)];
    const gpu::Vertex& v = mesh.vertices[c.index[k]];
    c.v[k] = glm::dvec3(transforms[c.object] * glm::dvec4(v.px, v.py, v.pz, 1.0)) - camera.position;
  }
  if (auto hit = intersectTriangle(c.v, dir)) {
    c.hit = true;
    c.t = hit->first;
    c.lambda = hit->second;
  }
  return c;
}

// What both judges check of their inputs, and the objects' transforms at the frame's animation time.
Result<std::vector<glm::dmat4>> judgedTransforms(const Scene& scene, const FrameResult& visbuf,
                                                 const FrameResult& forward, const JudgeOptions& options) {
  if (forward.width != visbuf.width || forward.height != visbuf.height)
    return makeError(ErrorCode::InvalidArgument, fmt::format("judge: frames of different sizes ({}x{}, {}x{})",
                                                             visbuf.width, visbuf.height, forward.width, forward.height));
  for (const FrameResult* f : {&visbuf, &forward}) {
    const std::vector<uint32_t>& lods = f->stats.cull.lodHistogram;
    if (f->drawnObjects.empty() && std::any_of(lods.begin() + std::min<size_t>(lods.size(), 1), lods.end(),
                                               [](uint32_t draws) { return draws > 0; }))
      return makeError(ErrorCode::InvalidArgument, "judge: a frame drew coarser LODs but has no drawn LODs to say "
                                                   "which (render it with readDraws, or lodErrorPixels 0)");
  }
  for (const Material& m : scene.materials)
    if (m.alphaMode == AlphaMode::Blend)
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("judge: material '{}' is BLEND: the transparency pass draws over the IDs, so "
                                   "they do not say what a pixel shows", m.name));
  std::vector<glm::dmat4> transforms(scene.objects.size());
  for (size_t i = 0; i < scene.objects.size(); ++i) transforms[i] = scene.objects[i].transform;
  if (!scene.rigidObjects.empty()) {
    const std::vector<glm::dmat4> posed = rigidObjectTransforms(scene, options.animationTime);
    for (size_t i = 0; i < posed.size(); ++i) transforms[scene.rigidObjects[i].object] = posed[i];
  }
  return transforms;
}

// Both paths' colour of one judged pixel against its exact colour: the accuracy sums, the heat map and the verdict.
class PixelScorer {
 public:
  PixelScorer(PixelJudgement& j, double tieTolerance) : j_(j), tie_(tieTolerance) {}
  void score(size_t i, const glm::dvec3& exact, const float* visbuf, const float* forward) {
    float* out = &j_.heatMap[4 * i];
    ++j_.judged;
    double errV = 0.0, errF = 0.0;
    addError(j_.visbuf, sumAbsV_, sumSqV_, visbuf, exact, errV);
    addError(j_.forward, sumAbsF_, sumSqF_, forward, exact, errF);
    out[0] = heat(errV);
    out[1] = heat(errF);
    if (std::equal(visbuf, visbuf + 3, forward)) return;
    ++j_.differing;
    const double margin = std::abs(errV - errF);
    if (margin <= tie_) {
      ++j_.ties;
    } else if (errV < errF) {
      ++j_.visbufCloser;
      j_.visbufMargin += margin;
      j_.visbufMaxMargin = std::max(j_.visbufMaxMargin, margin);
    } else {
      ++j_.forwardCloser;
      j_.forwardMargin += margin;
      j_.forwardMaxMargin = std::max(j_.forwardMaxMargin, margin);
    }
  }
  void finish() {
    if (j_.visbufCloser) j_.visbufMargin /= double(j_.visbufCloser);
    if (j_.forwardCloser) j_.forwardMargin /= double(j_.forwardCloser);
    const double samples = 3.0 * double(std::max<size_t>(j_.judged, 1));
    for (auto [a, sumAbs, sumSq] :
         {std::tuple{&j_.visbuf, sumAbsV_, sumSqV_}, std::tuple{&j_.forward, sumAbsF_, sumSqF_}}) {
      a->meanAbs = sumAbs / samples;
      a->psnr = sumSq > 0.0 ? 10.0 * std::log10(samples / sumSq) : INFINITY;
    }
  }

 private:
  PixelJudgement& j_;
  double tie_;
  double sumAbsV_ = 0.0, sumSqV_ = 0.0, sumAbsF_ = 0.0, sumSqF_ = 0.0;
};

PixelJudgement emptyJudgement(uint32_t w, uint32_t h) {
  PixelJudgement j;
  j.width = w;
  j.height = h;
  j.heatMap.assign(4 * size_t(w) * h, 0.0f);
  for (size_t i = 3; i < j.heatMap.size(); i += 4) j.heatMap[i] = 1.0f;
  return j;
}

}  // namespace

Result<PixelJudgement> judgePixels(const Scene& scene, const Camera& camera, const FrameResult& visbuf,
                                   const FrameResult& forward, const JudgeOptions& options) {
  const uint32_t w = visbuf.width, h = visbuf.height;
  const size_t pixels = size_t(w) * h;
  for (const FrameResult* f : {&visbuf, &forward})
    if (f->ids.size() != 2 * pixels || f->color.size() != 4 * pixels)
      return makeError(ErrorCode::InvalidArgument,
                       "judge: each frame needs single-sampled IDs and colour (readIds, readColor, msaa 1)");
  Result<std::vector<glm::dmat4>> transforms = judgedTransforms(scene, visbuf, forward, options);
  if (!transforms) return transforms.error();
  std::vector<uint8_t> skinned(scene.objects.size(), 0);
  for (const SkinnedObject& so : scene.skinnedObjects) skinned[so.object] = 1;
  const std::vector<uint32_t> lodsV = drawnLods(scene, visbuf), lodsF = drawnLods(scene, forward);
  const FrameMath math = computeFrameMath(camera, w, h);
  TextureReference textures(scene);

  PixelJudgement j = emptyJudgement(w, h);
  PixelScorer scorer(j, options.tieTolerance);
  const glm::dvec3 background(kBackgroundColor[0], kBackgroundColor[1], kBackgroundColor[2]);
  for (size_t i = 0; i < pixels; ++i) {
    const uint32_t idV = visbuf.ids[2 * i], idF = forward.ids[2 * i];
    if (idV == 0 && idF == 0) continue;
    ++j.covered;
    const uint32_t x = uint32_t(i % w), y = uint32_t(i / w);
    const PixelRay dir = pixelRay(math, x + 0.5, y + 0.5);
    // Each path's claim, with the ray's hit on it.
    Claim claims[2];
    size_t count = 0;
    for (int p = 0; p < 2; ++p) {
      const FrameResult& f = p == 0 ? visbuf : forward;
      const uint32_t id = f.ids[2 * i];
      if (id == 0) continue;
      const uint32_t lod = id <= scene.objects.size() ? (p == 0 ? lodsV : lodsF)[id - 1] : 0u;
      if (count == 1 && claims[0].object == id - 1 && claims[0].triangle == f.ids[2 * i + 1] && claims[0].lod == lod)
        continue;  // the same claim
      Result<Claim> c = makeClaim(scene, *transforms, camera, id, f.ids[2 * i + 1], lod, x, y, dir);
      if (!c) return c.error();
      claims[count++] = *c;
    }
    const bool agree = idV == idF && visbuf.ids[2 * i + 1] == forward.ids[2 * i + 1] && count == 1;
    // What the pixel shows: the one claim; where the paths disagree, the claim the ray enters first, else (a ray
    // through neither) the background where a path claims it, else the claim nearest to containing the centre.
    const Claim* truth = &claims[0];
    if (!agree) {
      ++j.coverageMismatch;
      truth = nullptr;
      for (size_t k = 0; k < count; ++k)
        if (claims[k].inside() && (!truth || claims[k].t < truth->t)) truth = &claims[k];
      if (!truth && idV != 0 && idF != 0)
        truth = claims[0].minLambda() >= claims[1].minLambda() ? &claims[0] : &claims[1];
    }
    glm::dvec3 exact = background;
    if (truth) {
      if (skinned[truth->object]) {
        ++j.notJudgedSkinned;
      } else if (!truth->hit) {
        ++j.notJudgedParallel;
      } else {
        exact = exactColor(scene, camera, math, textures, (*transforms)[truth->object], *truth, x + 0.5, y + 0.5);
        truth = nullptr;  // judged
      }
      if (truth) {
        j.heatMap[4 * i + 2] = 0.5f;
        continue;
      }
    }
    scorer.score(i, exact, &visbuf.color[4 * i], &forward.color[4 * i]);
  }
  scorer.finish();
  return j;
}

Result<PixelJudgement> judgeMsaaPixels(const Scene& scene, const Camera& camera, const FrameResult& visbuf,
                                       const FrameResult& forward, uint32_t samples, const JudgeOptions& options) {
  const uint32_t w = visbuf.width, h = visbuf.height;
  const size_t pixels = size_t(w) * h;
  if (samples != 2 && samples != 4)
    return makeError(ErrorCode::InvalidArgument, fmt::format("judge: {} samples (2 or 4)", samples));
  if (visbuf.ids.size() != 2 * pixels * samples || visbuf.color.size() != 4 * pixels ||
      forward.color.size() != 4 * pixels)
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("judge: the visbuf frame needs {}-sample IDs and colour (readIds, readColor, msaa "
                                 "{}), the forward frame its resolved colour", samples, samples));
  Result<std::vector<glm::dmat4>> transforms = judgedTransforms(scene, visbuf, forward, options);
  if (!transforms) return transforms.error();
  std::vector<uint8_t> skinned(scene.objects.size(), 0);
  for (const SkinnedObject& so : scene.skinnedObjects) skinned[so.object] = 1;
  const std::vector<uint32_t> lods = drawnLods(scene, visbuf);
  const FrameMath math = computeFrameMath(camera, w, h);
  TextureReference textures(scene);
  // Vulkan's standard sample locations (msaa_samples.glsl), pixel units from the top-left corner.
  static const glm::dvec2 kTwo[2] = {{0.75, 0.75}, {0.25, 0.25}};
  static const glm::dvec2 kFour[4] = {{0.375, 0.125}, {0.875, 0.375}, {0.125, 0.625}, {0.625, 0.875}};
  const glm::dvec2* at = samples == 2 ? kTwo : kFour;

  PixelJudgement j = emptyJudgement(w, h);
  PixelScorer scorer(j, options.tieTolerance);
  const glm::dvec3 background(kBackgroundColor[0], kBackgroundColor[1], kBackgroundColor[2]);
  for (size_t i = 0; i < pixels; ++i) {
    const uint32_t* ids = &visbuf.ids[2 * i * samples];
    bool any = false, agree = true;
    for (uint32_t s = 0; s < samples; ++s) {
      any |= ids[2 * s] != 0;
      agree &= ids[2 * s] == ids[0] && ids[2 * s + 1] == ids[1];
    }
    if (!any) continue;
    ++j.covered;
    j.coverageMismatch += !agree;  // here: pixels whose samples show different triangles (an edge)
    const uint32_t x = uint32_t(i % w), y = uint32_t(i / w);
    glm::dvec3 exact(0.0);
    bool judged = true;
    for (uint32_t s = 0; s < samples && judged; ++s) {
      if (ids[2 * s] == 0) {
        exact += background;
        continue;
      }
      const glm::dvec2 p = glm::dvec2(x, y) + at[s];
      const uint32_t lod = ids[2 * s] <= scene.objects.size() ? lods[ids[2 * s] - 1] : 0u;
      Result<Claim> c = makeClaim(scene, *transforms, camera, ids[2 * s], ids[2 * s + 1], lod, x, y,
                                  pixelRay(math, p.x, p.y));
      if (!c) return c.error();
      if (skinned[c->object]) {
        ++j.notJudgedSkinned;
        judged = false;
      } else if (!c->hit) {
        ++j.notJudgedParallel;
        judged = false;
      } else {
        exact += exactColor(scene, camera, math, textures, (*transforms)[c->object], *c, p.x, p.y);
      }
    }
    if (!judged) {
      j.heatMap[4 * i + 2] = 0.5f;
      continue;
    }
    scorer.score(i, exact / double(samples), &visbuf.color[4 * i], &forward.color[4 * i]);
  }
  scorer.finish();
  return j;
}

}  // namespace visbuf
