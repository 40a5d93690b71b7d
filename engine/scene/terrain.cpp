// The procedural heightfield of `render --scene terrain` (generate.h): one mesh near and far at once, the test
// scene of the cluster LOD hierarchy.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "visbuf/scene/generate.h"

namespace visbuf {

namespace {

// The terrain covers [-kTerrainExtent/2, kTerrainExtent/2]^2 in XZ whatever its vertex count (world units), so
// --terrain-size changes the sampling of one landscape, not its size.
constexpr double kTerrainExtent = 2048.0;

// Value noise on the integer lattice: a hash of (x, z, octave, seed) in [-1, 1] at each lattice point, blended with
// a quintic fade (C2, so the normals from the heights are smooth). Deterministic on every platform: integer hashing
// and double arithmetic only.
double latticeValue(int64_t x, int64_t z, uint32_t octave, uint64_t seed) {
  uint64_t h = seed ^ (uint64_t(x) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(z) * 0xC2B2AE3D27D4EB4Full) ^
               (uint64_t(octave) * 0x165667B19E3779F9ull);
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  h ^= h >> 31;
  return double(h >> 11) * 0x1.0p-52 - 1.0;
}

double valueNoise(double x, double z, uint32_t octave, uint64_t seed) {
  const double fx = std::floor(x), fz = std::floor(z);
  const int64_t ix = int64_t(fx), iz = int64_t(fz);
  auto fade = [](double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); };
  const double u = fade(x - fx), v = fade(z - fz);
  const double a = latticeValue(ix, iz, octave, seed), b = latticeValue(ix + 1, iz, octave, seed);
  const double c = latticeValue(ix, iz + 1, octave, seed), d = latticeValue(ix + 1, iz + 1, octave, seed);
  return (a + (b - a) * u) * (1.0 - v) + (c + (d - c) * u) * v;
}

// The landscape's octaves for a grid of `size` vertices a side: wavelengths from kTerrainExtent / 2 down to about
// four grid cells, so a finer grid samples finer detail (as a denser scan would) over the same large shapes.
uint32_t octavesFor(uint32_t size) {
  uint32_t octaves = 1;
  for (double wavelength = kTerrainExtent / 2.0; wavelength / 2.0 >= 4.0 * kTerrainExtent / (size - 1); wavelength /= 2.0)
    ++octaves;
  return std::min(octaves, 16u);
}

// Fractal height (world units) at (x, z): octaves of value noise, each half the wavelength and half the amplitude
// of the one before, rotated against each other so the lattices do not line up. At most +-180 units, typically +-60.
double terrainHeight(double x, double z, uint32_t octaves, uint64_t seed) {
  double height = 0.0, amplitude = 90.0, frequency = 2.0 / kTerrainExtent;
  const double cs = std::cos(0.5), sn = std::sin(0.5);
  for (uint32_t o = 0; o < octaves; ++o) {
    height += amplitude * valueNoise(x * frequency, z * frequency, o, seed);
    const double rx = cs * x - sn * z, rz = sn * x + cs * z;
    x = rx;
    z = rz;
    amplitude *= 0.5;
    frequency *= 2.0;
  }
  return height;
}

Status checkSize(uint32_t size) {
  if (size < kTerrainMinSize || size > kTerrainMaxSize)
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("terrain: --terrain-size {} must be in {}..{} vertices per side", size,
                                 kTerrainMinSize, kTerrainMaxSize));
  return {};
}

}  // namespace

Result<MeshSource> makeTerrainMesh(const TerrainParams& params) {
  if (Status s = checkSize(params.size); !s) return s.error();
  const uint32_t n = params.size;
  const uint32_t octaves = octavesFor(n);
  const double step = kTerrainExtent / (n - 1), origin = -kTerrainExtent / 2.0;
  MeshSource m;
  m.name = "terrain";
  const size_t vertices = size_t(n) * n;
  std::vector<double> height(vertices);
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i)
      height[size_t(j) * n + i] = terrainHeight(origin + i * step, origin + j * step, octaves, params.seed);
  m.positions.resize(vertices);
  m.normals.resize(vertices);
  m.uvs.resize(vertices);
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) {
      const size_t v = size_t(j) * n + i;
      m.positions[v] = glm::vec3(float(origin + i * step), float(height[v]), float(origin + j * step));
      // Central differences (one-sided at the edges) of the sampled heights: the normal of the surface drawn.
      const uint32_t i0 = i ? i - 1 : i, i1 = std::min(i + 1, n - 1), j0 = j ? j - 1 : j, j1 = std::min(j + 1, n - 1);
      const double dx = (height[size_t(j) * n + i1] - height[size_t(j) * n + i0]) / ((i1 - i0) * step);
      const double dz = (height[size_t(j1) * n + i] - height[size_t(j0) * n + i]) / ((j1 - j0) * step);
      m.normals[v] = glm::vec3(glm::normalize(glm::dvec3(-dx, 1.0, -dz)));
      m.uvs[v] = glm::vec2(float(i) / float(n - 1) * 64.0f, float(j) / float(n - 1) * 64.0f);  // 32-unit tiles
    }
  // Two triangles a cell, counter-clockwise seen from +Y; 6 (n-1)^2 indices (at most 402,653,184: 32-bit).
  m.indices.reserve(size_t(n - 1) * (n - 1) * 6);
  for (uint32_t j = 0; j + 1 < n; ++j)
    for (uint32_t i = 0; i + 1 < n; ++i) {
      const uint32_t a = j * n + i, b = a + 1, c = a + n + 1, d = a + n;
      m.indices.insert(m.indices.end(), {a, c, b, a, d, c});
    }
  return m;
}

Camera terrainCamera(const TerrainParams& params) {
  Camera camera;
  // Low and grazing: 3 units above the ground near the +Z edge, looking across the whole terrain to the far edge
  // with the horizon a little above the centre, so one frame holds triangles a few units away and kilometres away.
  // The eye's height is taken over the corners of the grid cell under it: the drawn surface there lies between them.
  const uint32_t octaves = octavesFor(params.size);
  const double step = kTerrainExtent / (params.size - 1), z = kTerrainExtent * 0.49;
  double ground = -INFINITY;
  for (double cx : {std::floor(kTerrainExtent / 2.0 / step) * step, std::ceil(kTerrainExtent / 2.0 / step) * step})
    for (double cz : {std::floor((z + kTerrainExtent / 2.0) / step) * step, std::ceil((z + kTerrainExtent / 2.0) / step) * step})
      ground = std::max(ground, terrainHeight(cx - kTerrainExtent / 2.0, cz - kTerrainExtent / 2.0, octaves, params.seed));
  const double eye = ground + 3.0;
  camera.position = {0.0, eye, z};
  camera.target = {0.0, eye - kTerrainExtent * 0.18, -kTerrainExtent * 0.5};
  camera.nearPlane = 0.05;
  return camera;
}

Result<Scene> makeTerrainScene(const TerrainParams& params) {
  Result<MeshSource> source = makeTerrainMesh(params);
  if (!source) return source.error();
  // The per-object LOD chain: coarse levels only, each a quarter of the previous one (the default chain's dense sweep
  // of fine levels simplifies the whole mesh dozens of times: 29 s at 513^2 vertices against 5.5 s this way, on the
  // 2-core machine), and none above 2^21 triangles, where each level simplifies and measures the whole mesh again
  // (4097^2: 206 s without a chain, 29 minutes with 8 levels). The default grazing view draws level 0 anyway; the
  // cluster LOD hierarchy (cluster_lod.h) is what makes such a mesh cheap from afar.
  MeshBuildOptions options;
  options.lodRatio = 0.25f;
  options.fineBelowTriangles = 0;
  options.maxLods = source->indices.size() / 3 > (size_t{1} << 21) ? 1 : 8;
  Result<Mesh> mesh = buildMesh(*source, options);
  if (!mesh) return mesh.error();
  Scene scene;
  scene.name = "terrain";
  scene.meshes.push_back(std::move(mesh.value()));
  Material ground{"ground", {0.55f, 0.60f, 0.42f, 1.0f}};
  ground.metallic = 0.0f;
  ground.roughness = 0.85f;
  scene.materials.push_back(ground);
  scene.objects.push_back({glm::dmat4(1.0), 0, 0});
  scene.defaultCamera = terrainCamera(params);
  scene.lightDirection = glm::normalize(glm::vec3(0.4f, 0.6f, 0.25f));
  return scene;
}

}  // namespace visbuf
