#include "visbuf/scene/generate.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

namespace visbuf {

uint64_t Rng::next() {
  uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

MeshSource makeTorusKnot(uint32_t segments, uint32_t sides) {
  MeshSource m;
  m.name = "torus-knot";
  const double p = 2.0, q = 3.0, tube = 0.12, scale = 1.0 / 1.45;
  auto curve = [&](double t) {
    double r = 2.0 + std::cos(q * t);
    return glm::dvec3(r * std::cos(p * t), r * std::sin(p * t), -std::sin(q * t)) * 0.5;
  };
  for (uint32_t i = 0; i < segments; ++i) {
    double t = 2.0 * M_PI * i / segments;
    glm::dvec3 c = curve(t);
    glm::dvec3 tangent = glm::normalize(curve(t + 1e-4) - curve(t - 1e-4));
    glm::dvec3 normal = glm::normalize(curve(t + 1e-4) + curve(t - 1e-4) - 2.0 * c);
    glm::dvec3 binormal = glm::normalize(glm::cross(tangent, normal));
    normal = glm::cross(binormal, tangent);
    for (uint32_t j = 0; j < sides; ++j) {
      double a = 2.0 * M_PI * j / sides;
      glm::dvec3 dir = std::cos(a) * normal + std::sin(a) * binormal;
      m.positions.push_back(glm::vec3((c + tube * dir) * scale));
      m.normals.push_back(glm::vec3(dir));
      m.uvs.push_back(glm::vec2(float(i) / segments, float(j) / sides));
    }
  }
  for (uint32_t i = 0; i < segments; ++i)
    for (uint32_t j = 0; j < sides; ++j) {
      uint32_t a = i * sides + j, b = ((i + 1) % segments) * sides + j;
      uint32_t c = ((i + 1) % segments) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
  return m;
}

namespace {
// Adds an n x n grid on the plane origin + u*s + v*t (s,t in [0,1]), facing cross(u, v).
void addQuadGrid(MeshSource& m, glm::vec3 origin, glm::vec3 u, glm::vec3 v, uint32_t n) {
  glm::vec3 normal = glm::normalize(glm::cross(u, v));
  uint32_t base = uint32_t(m.positions.size());
  for (uint32_t y = 0; y <= n; ++y)
    for (uint32_t x = 0; x <= n; ++x) {
      float s = float(x) / n, t = float(y) / n;
      m.positions.push_back(origin + u * s + v * t);
      m.normals.push_back(normal);
      m.uvs.push_back({s, t});
    }
  for (uint32_t y = 0; y < n; ++y)
    for (uint32_t x = 0; x < n; ++x) {
      uint32_t a = base + y * (n + 1) + x, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
    }
}
}  // namespace

MeshSource makeBox(uint32_t n) {
  MeshSource m;
  m.name = "box";
  const float h = 0.5f;
  addQuadGrid(m, {-h, -h, h}, {1, 0, 0}, {0, 1, 0}, n);    // +Z
  addQuadGrid(m, {h, -h, -h}, {-1, 0, 0}, {0, 1, 0}, n);   // -Z
  addQuadGrid(m, {h, -h, h}, {0, 0, -1}, {0, 1, 0}, n);    // +X
  addQuadGrid(m, {-h, -h, -h}, {0, 0, 1}, {0, 1, 0}, n);   // -X
  addQuadGrid(m, {-h, h, h}, {1, 0, 0}, {0, 0, -1}, n);    // +Y
  addQuadGrid(m, {-h, -h, -h}, {1, 0, 0}, {0, 0, 1}, n);   // -Y
  return m;
}

MeshSource makeGround(uint32_t n) {
  MeshSource m;
  m.name = "ground";
  addQuadGrid(m, {-0.5f, 0.0f, 0.5f}, {1, 0, 0}, {0, 0, -1}, n);
  return m;
}

namespace {
std::vector<Material> palette() {
  std::vector<Material> p = {{"clay", {0.80f, 0.45f, 0.30f, 1.0f}}, {"sage", {0.45f, 0.65f, 0.40f, 1.0f}},
                             {"slate", {0.35f, 0.45f, 0.70f, 1.0f}}, {"sand", {0.85f, 0.78f, 0.55f, 1.0f}},
                             {"plum", {0.60f, 0.35f, 0.60f, 1.0f}}, {"ash", {0.70f, 0.70f, 0.72f, 1.0f}}};
  // Dielectrics of varied roughness (glTF's default metallic factor, 1, would make them metals).
  const float roughness[] = {0.9f, 0.6f, 0.5f, 0.8f, 0.55f, 0.7f};
  for (size_t i = 0; i < p.size(); ++i) {
    p[i].metallic = 0.0f;
    p[i].roughness = roughness[i];
  }
  return p;
}
}  // namespace

Result<Scene> makeFieldScene(const FieldParams& params) {
  if (params.objects == 0) return makeError(ErrorCode::InvalidArgument, "field: --objects must be at least 1");
  Scene scene;
  scene.name = "field";
  Result<Mesh> mesh = buildMesh(params.mesh ? *params.mesh : makeTorusKnot());
  if (!mesh) return mesh.error();
  // Normalise the instanced mesh to unit bounding radius so scale [2,4) means the same for any mesh.
  glm::vec4 s = mesh->boundsSphere;
  const double unit = 1.0 / std::max(double(s.w), 1e-12);
  scene.meshes.push_back(std::move(mesh.value()));
  scene.materials = palette();
  Rng rng(params.seed);
  scene.objects.reserve(params.objects);
  for (uint32_t i = 0; i < params.objects; ++i) {
    glm::dvec3 pos(rng.uniform(-params.extent, params.extent), rng.uniform(-params.extent, params.extent),
                   rng.uniform(-params.extent, params.extent));
    double scale = rng.uniform(2.0, 4.0);
    glm::dvec3 axis(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (glm::length(axis) < 1e-6) axis = {0, 1, 0};
    double angle = glm::radians(rng.uniform(0.0, 90.0));
    glm::dmat4 t = glm::translate(glm::dmat4(1.0), pos) * glm::rotate(glm::dmat4(1.0), angle, glm::normalize(axis)) *
                   glm::scale(glm::dmat4(1.0), glm::dvec3(scale * unit)) *
                   glm::translate(glm::dmat4(1.0), -glm::dvec3(glm::vec3(s)));
    scene.objects.push_back({t, 0, uint32_t(i % scene.materials.size())});
  }
  scene.defaultCamera.position = {0.0, 0.0, params.extent * 1.6};
  scene.defaultCamera.target = {0.0, 0.0, 0.0};
  scene.defaultCamera.nearPlane = 0.1;
  return scene;
}

Result<Scene> makeCityScene(const CityParams& params) {
  if (params.objects < 16) return makeError(ErrorCode::InvalidArgument, "city: --objects must be at least 16");
  Scene scene;
  scene.name = "city";
  for (MeshSource src : {makeBox(8), makeGround(64), makeTorusKnot(48, 12)}) {
    Result<Mesh> m = buildMesh(src);
    if (!m) return m.error();
    scene.meshes.push_back(std::move(m.value()));
  }
  scene.materials = palette();
  scene.materials.push_back({"asphalt", {0.25f, 0.25f, 0.27f, 1.0f}});
  scene.materials.back().metallic = 0.0f;
  const uint32_t asphalt = uint32_t(scene.materials.size() - 1);
  // Each block: one building and ~8 clutter objects along its kerb.
  const uint32_t perBlock = 9;
  const uint32_t blocks = std::max<uint32_t>(1, (params.objects - 1) / perBlock);
  const uint32_t grid = std::max<uint32_t>(2, uint32_t(std::ceil(std::sqrt(double(blocks)))));
  const double pitch = 40.0, street = 12.0;
  const double half = grid * pitch * 0.5;
  Rng rng(params.seed);
  // Ground sits at y = 0; buildings start below it so no surfaces are coplanar (no depth ties).
  scene.objects.push_back({glm::scale(glm::dmat4(1.0), glm::dvec3(grid * pitch + 200.0, 1.0, grid * pitch + 200.0)),
                           1, asphalt});
  uint32_t placed = 0;
  for (uint32_t gz = 0; gz < grid && placed < blocks; ++gz)
    for (uint32_t gx = 0; gx < grid && placed < blocks; ++gx, ++placed) {
      double cx = -half + (gx + 0.5) * pitch, cz = -half + (gz + 0.5) * pitch;
      double w = pitch - street - rng.uniform(0.0, 6.0), d = pitch - street - rng.uniform(0.0, 6.0);
      double h = rng.uniform(8.0, 60.0);
      glm::dmat4 t = glm::translate(glm::dmat4(1.0), glm::dvec3(cx, h * 0.5 - 0.5, cz)) *
                     glm::scale(glm::dmat4(1.0), glm::dvec3(w, h + 1.0, d));
      scene.objects.push_back({t, 0, uint32_t(rng.next() % 6)});
      for (uint32_t k = 0; k < perBlock - 1; ++k) {
        // Clutter on the pavement ring around the building.
        double side = double(k % 4);
        double along = rng.uniform(-0.45, 0.45) * (pitch - street);
        double off = (pitch - street) * 0.5 + 2.5;
        glm::dvec3 p = side == 0 ? glm::dvec3(along, 0, off) : side == 1 ? glm::dvec3(along, 0, -off)
                     : side == 2 ? glm::dvec3(off, 0, along) : glm::dvec3(-off, 0, along);
        double sc = rng.uniform(0.8, 1.6);
        glm::dmat4 c = glm::translate(glm::dmat4(1.0), glm::dvec3(cx, sc * 1.05, cz) + p) *
                       glm::rotate(glm::dmat4(1.0), rng.uniform(0.0, 6.28), glm::dvec3(0, 1, 0)) *
                       glm::scale(glm::dmat4(1.0), glm::dvec3(sc));
        scene.objects.push_back({c, 2, uint32_t(rng.next() % 6)});
      }
    }
  // Street level, looking down the avenue between the first two columns of blocks.
  double streetX = -half + pitch;
  scene.defaultCamera.position = {streetX, 1.7, half - 5.0};
  scene.defaultCamera.target = {streetX + 8.0, 3.0, -half};
  scene.defaultCamera.nearPlane = 0.05;
  scene.lightDirection = glm::normalize(glm::vec3(0.5f, 0.8f, 0.3f));
  return scene;
}

namespace {
// The asset's punctual lights for one copy placed by `place` (uniform scale `scale`): point and spot lights
// moved with it, their range scaled and their intensity by scale^2 (the copy is lit as the asset at its own size);
// directional lights (no position, no falloff) once, or N copies would be N times as bright.
void copyLights(const std::vector<PointLight>& lights, const glm::dmat4& place, double scale, bool first,
                std::vector<PointLight>& out) {
  for (PointLight l : lights) {
    if (l.type == LightType::Directional) {
      if (first) out.push_back(l);  // the asset's sky, not turned with any copy's heading
      continue;
    }
    l.position = glm::dvec3(place * glm::dvec4(l.position, 1.0));
    l.direction = glm::vec3(glm::normalize(glm::dmat3(place) * glm::dvec3(l.direction)));
    if (l.range > 0.0f) l.range = float(l.range * scale);
    l.intensity = float(l.intensity * scale * scale);
    out.push_back(l);
  }
}
}  // namespace

Result<Scene> makeAnimatedField(const Scene& asset, const AnimatedFieldParams& params) {
  if (asset.objects.empty()) return makeError(ErrorCode::InvalidArgument, "animated field: the asset has no objects");
  if (params.instances == 0) return makeError(ErrorCode::InvalidArgument, "animated field: 0 instances");
  Scene s;
  s.name = "animated-field";
  s.meshes = asset.meshes;
  s.materials = asset.materials;
  s.textures = asset.textures;
  s.textureClasses = asset.textureClasses;
  s.nodes = asset.nodes;
  s.skins = asset.skins;
  s.animations = asset.animations;
  s.lightDirection = asset.lightDirection;
  s.lightIntensity = asset.lightIntensity;
  // The asset's rest-pose bounds (skinned objects: their node transforms place the bind pose).
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const Object& o : asset.objects) {
    const glm::dvec4 b = objectBoundsWorld(asset, o);
    lo = glm::min(lo, glm::dvec3(b) - b.w);
    hi = glm::max(hi, glm::dvec3(b) + b.w);
  }
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double unit = 1.0 / std::max(0.5 * glm::length(hi - lo), 1e-9);
  const uint32_t side = uint32_t(std::ceil(std::sqrt(double(params.instances))));
  std::vector<int32_t> skinnedIndex(asset.objects.size(), -1), rigidIndex(asset.objects.size(), -1);
  for (size_t i = 0; i < asset.skinnedObjects.size(); ++i) skinnedIndex[asset.skinnedObjects[i].object] = int32_t(i);
  for (size_t i = 0; i < asset.rigidObjects.size(); ++i) rigidIndex[asset.rigidObjects[i].object] = int32_t(i);
  Rng rng(params.seed);
  for (uint32_t k = 0; k < params.instances; ++k) {
    const double x = (double(k % side) - 0.5 * side + rng.uniform(-0.3, 0.3)) * params.spacing;
    const double z = (double(k / side) - 0.5 * side + rng.uniform(-0.3, 0.3)) * params.spacing;
    const glm::dmat4 place = glm::translate(glm::dmat4(1.0), glm::dvec3(x, 0.0, z)) *
                             glm::rotate(glm::dmat4(1.0), rng.uniform(0.0, 6.283185307179586), glm::dvec3(0, 1, 0)) *
                             glm::scale(glm::dmat4(1.0), glm::dvec3(unit)) *
                             glm::translate(glm::dmat4(1.0), -centre);
    const double phase = rng.uniform();
    copyLights(asset.pointLights, place, unit, k == 0, s.pointLights);
    for (size_t i = 0; i < asset.objects.size(); ++i) {
      const Object& o = asset.objects[i];
      s.objects.push_back({place * o.transform, o.mesh, o.material});
      if (rigidIndex[i] >= 0) {  // its own placement and phase; its transform the pose at time 0
        RigidObject ro = asset.rigidObjects[size_t(rigidIndex[i])];
        ro.object = uint32_t(s.objects.size() - 1);
        ro.placement = place * ro.placement;
        if (ro.clip >= 0 && size_t(ro.clip) < s.animations.size())
          ro.timeOffset += phase * s.animations[size_t(ro.clip)].duration;
        s.objects.back().transform = rigidObjectStartTransform(s, ro, place * o.transform);
        s.rigidObjects.push_back(ro);
      }
      if (skinnedIndex[i] < 0) continue;
      SkinnedObject so = asset.skinnedObjects[size_t(skinnedIndex[i])];
      so.object = uint32_t(s.objects.size() - 1);
      so.placement = place * so.placement;
      const bool hasClip = so.clip >= 0 && size_t(so.clip) < s.animations.size();
      so.timeOffset = hasClip ? phase * s.animations[size_t(so.clip)].duration : 0.0;
      s.skinnedObjects.push_back(so);
    }
  }
  const double half = 0.5 * side * params.spacing;
  s.defaultCamera.position = {0.0, 0.3 * half + 1.5, half + 3.0};
  s.defaultCamera.target = {0.0, 0.0, 0.3 * half};
  s.defaultCamera.nearPlane = 0.05;
  return s;
}

Result<Scene> makeFoliageScene(const FoliageParams& params) {
  if (params.cards == 0) return makeError(ErrorCode::InvalidArgument, "foliage: --objects must be at least 1");
  MeshSource card;
  card.name = "card";
  card.positions = {{-0.5f, -0.5f, 0.0f}, {0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {-0.5f, 0.5f, 0.0f}};
  card.normals.assign(4, glm::vec3(0.0f, 0.0f, 1.0f));
  card.uvs = {{0.0f, 1.0f}, {1.0f, 1.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}};
  card.colors = {0x00ffffffu, 0xffffffffu, 0xffffffffu, 0x00ffffffu};  // alpha 0 at x = -0.5, 1 at x = +0.5
  card.indices = {0, 1, 2, 0, 2, 3};
  Result<Mesh> mesh = buildMesh(card);
  if (!mesh) return mesh.error();
  Scene scene;
  scene.name = params.masked ? "foliage" : "foliage-opaque";
  scene.meshes.push_back(std::move(mesh.value()));
  for (glm::vec4 c : {glm::vec4(0.25f, 0.6f, 0.2f, 1.0f), glm::vec4(0.4f, 0.7f, 0.25f, 1.0f),
                      glm::vec4(0.55f, 0.6f, 0.2f, 1.0f)}) {
    Material m;
    m.name = "leaf";
    m.baseColor = c;
    m.alphaMode = params.masked ? AlphaMode::Mask : AlphaMode::Opaque;
    m.alphaCutoff = 0.5f;
    m.doubleSided = true;
    m.metallic = 0.0f;
    scene.materials.push_back(m);
  }
  Rng rng(params.seed);
  scene.objects.reserve(params.cards);
  for (uint32_t i = 0; i < params.cards; ++i) {
    glm::dvec3 pos(rng.uniform(-params.extent, params.extent), rng.uniform(0.0, params.extent / 3.0),
                   rng.uniform(-params.extent, params.extent));
    glm::dvec3 axis(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    if (glm::length(axis) < 1e-6) axis = {0, 1, 0};
    const double angle = rng.uniform(0.0, 2.0 * M_PI), scale = rng.uniform(1.0, 3.0);
    glm::dmat4 t = glm::translate(glm::dmat4(1.0), pos) * glm::rotate(glm::dmat4(1.0), angle, glm::normalize(axis)) *
                   glm::scale(glm::dmat4(1.0), glm::dvec3(scale));
    scene.objects.push_back({t, 0, uint32_t(i % scene.materials.size())});
  }
  scene.defaultCamera.position = {0.0, params.extent / 4.0, params.extent * 1.3};
  scene.defaultCamera.target = {0.0, params.extent / 8.0, 0.0};
  scene.defaultCamera.nearPlane = 0.1;
  return scene;
}

}  // namespace visbuf

namespace visbuf {

namespace {
// A class of `layers` square images, level 0 from texel(layer, x, y), the chain by 2x2 box filtering of the stored
// values (sRGB values averaged as stored: close enough for a benchmark texture).
template <typename Texel>
TextureClass proceduralClass(uint32_t size, ColorSpace space, uint32_t layers, Texel texel) {
  TextureClass c;
  c.size = size;
  c.colorSpace = space;
  c.layers = layers;
  c.mipCount = TextureClass::mipCountFor(size);
  c.texels.resize(c.totalBytes());
  for (uint32_t l = 0; l < layers; ++l) {
    uint8_t* p = c.texels.data() + c.offset(0, l);
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x) {
        const glm::u8vec4 t = texel(l, x, y);
        for (int k = 0; k < 4; ++k) p[4 * (y * size + x) + k] = t[k];
      }
    for (uint32_t m = 1; m < c.mipCount; ++m) {
      const uint32_t n = std::max(size >> m, 1u), prev = std::max(size >> (m - 1), 1u);
      const uint8_t* src = c.texels.data() + c.offset(m - 1, l);
      uint8_t* dst = c.texels.data() + c.offset(m, l);
      for (uint32_t y = 0; y < n; ++y)
        for (uint32_t x = 0; x < n; ++x)
          for (int k = 0; k < 4; ++k) {
            uint32_t sum = 0;
            for (uint32_t dy = 0; dy < 2; ++dy)
              for (uint32_t dx = 0; dx < 2; ++dx)
                sum += src[4 * (std::min(2 * y + dy, prev - 1) * prev + std::min(2 * x + dx, prev - 1)) + k];
            dst[4 * (y * n + x) + k] = uint8_t((sum + 2) / 4);
          }
    }
  }
  return c;
}
}  // namespace

Status applyGeneratedMaterials(Scene& scene, uint32_t count, uint64_t seed) {
  if (count == 0) return makeError(ErrorCode::InvalidArgument, "--materials must be at least 1");
  if (!scene.textures.empty() || !scene.textureClasses.empty())
    return makeError(ErrorCode::InvalidArgument, "--materials replaces the materials of a generated scene (field, "
                                                 "city); this scene has textures of its own");
  constexpr uint32_t kColorLayers = 4, kDataLayers = 2;
  scene.textureClasses.push_back(proceduralClass(128, ColorSpace::Srgb, kColorLayers, [](uint32_t l, uint32_t x, uint32_t y) {
    const uint32_t cells = 4u << l;  // 4, 8, 16, 32 checks a side; odd layers striped
    const bool on = l % 2 ? (x * cells / 128) % 2 == 0 : ((x * cells / 128) + (y * cells / 128)) % 2 == 0;
    return on ? glm::u8vec4(235, 225, 200, 255) : glm::u8vec4(uint8_t(40 + 50 * l), 70, 90, 255);
  }));
  scene.textureClasses.push_back(proceduralClass(64, ColorSpace::Linear, kDataLayers, [](uint32_t l, uint32_t x, uint32_t y) {
    const uint32_t h = (x * 73856093u) ^ (y * 19349663u) ^ (l * 83492791u);
    return glm::u8vec4(255, uint8_t(96 + (h & 127)), uint8_t(l ? (h >> 8) & 255 : 0), 255);  // G roughness, B metal
  }));
  for (uint32_t c = 0; c < 2; ++c)
    for (uint32_t l = 0; l < scene.textureClasses[c].layers; ++l) {
      Texture t;
      t.name = std::string("generated ") + (c ? "data " : "colour ") + std::to_string(l);
      t.colorSpace = scene.textureClasses[c].colorSpace;
      t.sizeClass = c;
      t.layer = l;
      t.originalWidth = t.originalHeight = scene.textureClasses[c].size;
      scene.textures.push_back(t);
    }
  Rng rng(seed ^ 0x6d61746572ull);
  const Material first = scene.materials.empty() ? Material{} : scene.materials.front();
  scene.materials.clear();
  for (uint32_t i = 0; i < count; ++i) {
    Material m;
    m.alphaMode = first.alphaMode;
    m.alphaCutoff = first.alphaCutoff;
    m.doubleSided = first.doubleSided;
    m.name = "generated " + std::to_string(i);
    m.baseColor = glm::vec4(float(rng.uniform(0.3, 1.0)), float(rng.uniform(0.3, 1.0)), float(rng.uniform(0.3, 1.0)), 1.0f);
    m.metallic = float(rng.uniform(0.0, 0.3));
    m.roughness = float(rng.uniform(0.3, 0.9));
    if (i % 4 != 3) {
      m.baseColorTexture.texture = m.baseColorTexture.baked = int32_t(i % kColorLayers);
      const float scale = float(1 << (i % 3));
      m.baseColorTexture.transform = glm::mat3x2(glm::vec2(scale, 0.0f), glm::vec2(0.0f, scale), glm::vec2(0.0f));
      if (i % 2 == 0)
        m.metallicRoughnessTexture.texture = m.metallicRoughnessTexture.baked = int32_t(kColorLayers + (i / 2) % kDataLayers);
    }
    scene.materials.push_back(m);
  }
  for (uint32_t i = 0; i < scene.objects.size(); ++i) {
    uint64_t h = (uint64_t(i) + 1) * 0x9E3779B97F4A7C15ull ^ seed;
    h = (h ^ (h >> 31)) * 0xBF58476D1CE4E5B9ull;
    scene.objects[i].material = uint32_t((h ^ (h >> 29)) % count);
  }
  return {};
}

}  // namespace visbuf
