// The mesh build on adversarial meshes (fans, stacked copies, slivers, one huge triangle among small ones,
// coincident vertices): the nearest-triangle tree against brute force, the error measure as an upper bound of the
// brute-force error, degenerate triangles dropped without dropping any that can open up, and meshlet order kept.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <span>

#include <glm/gtc/constants.hpp>
#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include "visbuf/scene/clusters.h"
#include "visbuf/scene/generate.h"
#include "visbuf/scene/mesh_error.h"
#include "visbuf/scene/scene.h"

using namespace visbuf;

namespace {

struct Soup {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
};

// A disc of n thin triangles around one centre vertex (every triangle's box holds the centre).
Soup fan(uint32_t n, float radius = 1.0f) {
  Soup s;
  s.positions.push_back({0, 0, 0});
  for (uint32_t i = 0; i < n; ++i) {
    const double a = 2.0 * glm::pi<double>() * i / n;
    s.positions.push_back({float(radius * std::cos(a)), float(radius * std::sin(a)), 0.0f});
  }
  for (uint32_t i = 0; i < n; ++i) s.indices.insert(s.indices.end(), {0, 1 + i, 1 + (i + 1) % n});
  return s;
}

// `copies` copies of one large triangle, each with its own vertices (so nothing merges them).
Soup stacked(uint32_t copies) {
  Soup s;
  for (uint32_t i = 0; i < copies; ++i) {
    s.positions.insert(s.positions.end(), {{-100, -100, 0}, {100, -100, 0}, {0, 100, 0}});
    s.indices.insert(s.indices.end(), {3 * i, 3 * i + 1, 3 * i + 2});
  }
  return s;
}

// Long slivers crossing a cube along random diagonals: every box is most of the cube.
Soup slivers(uint32_t n, uint32_t seed) {
  Soup s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (uint32_t i = 0; i < n; ++i) {
    const glm::vec3 a(u(rng), u(rng), u(rng)), b = -a, off(u(rng) * 1e-3f, u(rng) * 1e-3f, u(rng) * 1e-3f);
    s.positions.insert(s.positions.end(), {a, b, a * 0.5f + off});
    s.indices.insert(s.indices.end(), {3 * i, 3 * i + 1, 3 * i + 2});
  }
  return s;
}

// A grid of small triangles with one huge triangle across it.
Soup hugeAmongSmall(uint32_t side) {
  Soup s;
  for (uint32_t y = 0; y <= side; ++y)
    for (uint32_t x = 0; x <= side; ++x) s.positions.push_back({float(x), float(y), std::sin(float(x + y))});
  for (uint32_t y = 0; y < side; ++y)
    for (uint32_t x = 0; x < side; ++x) {
      const uint32_t i = y * (side + 1) + x;
      s.indices.insert(s.indices.end(), {i, i + 1, i + side + 1, i + 1, i + side + 2, i + side + 1});
    }
  const uint32_t h = uint32_t(s.positions.size());
  s.positions.insert(s.positions.end(), {{-1e4f, -1e4f, 3}, {1e4f, -1e4f, 3}, {0, 1e4f, 3}});
  s.indices.insert(s.indices.end(), {h, h + 1, h + 2});
  return s;
}

double bruteDistance(const Soup& s, std::span<const uint32_t> indices, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::max();
  for (size_t t = 0; t + 2 < indices.size(); t += 3)
    best = std::min(best, pointTriangleDistance(p, glm::dvec3(s.positions[indices[t]]),
                                                glm::dvec3(s.positions[indices[t + 1]]),
                                                glm::dvec3(s.positions[indices[t + 2]])));
  return best;
}

// The two-sided sampled error by brute force, sampled as measureSimplificationError documents.
double bruteError(const Soup& s, std::span<const uint32_t> full, std::span<const uint32_t> level) {
  double error = 0.0;
  for (uint32_t i : full) error = std::max(error, bruteDistance(s, level, glm::dvec3(s.positions[i])));
  for (size_t t = 0; t + 2 < level.size(); t += 3) {
    const glm::dvec3 a(s.positions[level[t]]), b(s.positions[level[t + 1]]), c(s.positions[level[t + 2]]);
    for (const glm::dvec3& q : {(a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5, (a + b + c) / 3.0})
      error = std::max(error, bruteDistance(s, full, q));
  }
  return error;
}

std::vector<std::pair<const char*, Soup>> adversarial() {
  std::vector<std::pair<const char*, Soup>> out;
  out.emplace_back("fan", fan(3000));
  out.emplace_back("stacked", stacked(2000));
  out.emplace_back("slivers", slivers(1500, 5));
  out.emplace_back("huge among small", hugeAmongSmall(30));
  return out;
}

std::vector<glm::dvec3> queryPoints(uint32_t seed, double extent) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  std::vector<glm::dvec3> out;
  for (int i = 0; i < 200; ++i) out.emplace_back(u(rng), u(rng), u(rng) * 0.2);
  out.emplace_back(0.0, 0.0, 0.0);
  out.emplace_back(1e17, -3e16, 5.0);
  return out;
}

}  // namespace

// Exact: the tree's nearest distance equals brute force over every triangle, bit for bit (the same double-precision
// point-triangle distance), on meshes that made the uniform grid it replaces quadratic or overflow.
TEST(TriangleBvh, ExactAgainstBruteForceOnAdversarialMeshes) {
  for (const auto& [name, s] : adversarial()) {
    const TriangleBvh tree(s.positions, s.indices);
    for (const glm::dvec3& p : queryPoints(11, 120.0)) {
      const double exact = bruteDistance(s, s.indices, p);
      EXPECT_EQ(tree.distance(p), exact) << name << " at " << p.x << "," << p.y << "," << p.z;
      // With `enough`: some triangle's distance, the nearest or one within `enough`.
      const double enough = exact * 1.5 + 0.01;
      const double early = tree.distance(p, enough);
      EXPECT_GE(early, exact) << name;
      EXPECT_TRUE(early == exact || early <= enough) << name;
    }
  }
}

// Budgeted searches never fall below the exact distance (an upper bound), even with no budget at all, and are finite.
TEST(TriangleBvh, BudgetedSearchIsAnUpperBound) {
  for (const auto& [name, s] : adversarial()) {
    const TriangleBvh tree(s.positions, s.indices);
    for (const glm::dvec3& p : queryPoints(12, 50.0))
      for (uint64_t start : {0ull, 1ull, 7ull, 100ull}) {
        uint64_t budget = start;
        const double d = tree.distance(p, -1.0, budget);
        EXPECT_GE(d, bruteDistance(s, s.indices, p)) << name << " budget " << start;
        EXPECT_LT(d, std::numeric_limits<double>::max()) << name;
      }
  }
  const std::vector<glm::vec3> none;
  const std::vector<uint32_t> noIndices;
  EXPECT_EQ(TriangleBvh(none, noIndices).distance({0, 0, 0}), std::numeric_limits<double>::max());
}

// The measured error bounds the brute-force two-sided error from above on adversarial meshes (a simplified level
// that drops half of the triangles), and equals it on an ordinary mesh, where the work budget is never reached.
TEST(MeshError, MeasureBoundsTheBruteForceErrorOnAdversarialMeshes) {
  for (const auto& [name, s] : adversarial()) {
    std::vector<uint32_t> level;
    for (size_t t = 0; t + 2 < s.indices.size(); t += 6) level.insert(level.end(), &s.indices[t], &s.indices[t + 3]);
    const double brute = bruteError(s, s.indices, level);
    EXPECT_GE(measureSimplificationError(s.positions, s.indices, level), brute * (1.0 - 1e-12)) << name;
  }
  Result<Mesh> knot = buildMesh(makeTorusKnot(24, 6));
  ASSERT_TRUE(knot.ok());
  Soup k;
  for (uint32_t v = 0; v < knot->vertices.size(); ++v) k.positions.push_back(knot->position(v));
  const Lod& l0 = knot->lods[0];
  const Lod& l1 = knot->lods[1];
  const std::span<const uint32_t> full(knot->indices.data() + l0.firstIndex, l0.indexCount);
  const std::span<const uint32_t> level(knot->indices.data() + l1.firstIndex, l1.indexCount);
  EXPECT_EQ(measureSimplificationError(k.positions, full, level), bruteError(k, full, level));
}

namespace {

MeshSource sourceOf(const Soup& s) {
  MeshSource m;
  m.name = "soup";
  m.positions = s.positions;
  m.normals.assign(s.positions.size(), glm::vec3(0, 0, 1));
  m.indices = s.indices;
  return m;
}

std::vector<std::array<uint32_t, 3>> trianglesAt(const Mesh& m, size_t lod) {
  std::vector<std::array<uint32_t, 3>> out;
  const Lod& l = m.lods[lod];
  for (uint32_t i = 0; i < l.indexCount; i += 3) {
    std::array<uint32_t, 3> t{m.indices[l.firstIndex + i], m.indices[l.firstIndex + i + 1],
                              m.indices[l.firstIndex + i + 2]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    out.push_back(t);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// Triangles with two corners at the same place cover no pixel and are dropped; the rest are all kept.
TEST(MeshBuild, DropsTrianglesThatCoverNoPixel) {
  Soup s = fan(8);
  const uint32_t n = uint32_t(s.positions.size());
  s.positions.push_back(s.positions[1]);  // a second vertex at rim vertex 1's position
  s.indices.insert(s.indices.end(), {0, 0, 2, 3, 3, 3, 1, n, 2});  // repeated indices; coincident corners
  Result<Mesh> m = buildMesh(sourceOf(s));
  ASSERT_TRUE(m.ok()) << m.error().message;
  EXPECT_EQ(m->lods[0].indexCount, 8u * 3);
  EXPECT_EQ(m->vertices.size(), 9u);  // the extra vertex is used by no kept triangle
  // Nothing but degenerate triangles: the mesh keeps one (it draws nothing) and still builds.
  Soup only;
  only.positions.assign(30, glm::vec3(0.0f));
  for (uint32_t i = 0; i < 30; ++i) only.indices.push_back(i);
  Result<Mesh> d = buildMesh(sourceOf(only));
  ASSERT_TRUE(d.ok()) << d.error().message;
  EXPECT_EQ(d->lods[0].indexCount, 3u);
}

// A triangle collapsed at rest that a morph target opens is not dropped: its corners are not at the same place in
// every pose.
TEST(MeshBuild, KeepsCollapsedTrianglesAMorphTargetOpens) {
  MeshSource m = sourceOf(fan(8));
  const uint32_t a = uint32_t(m.positions.size());
  m.positions.insert(m.positions.end(), 3, glm::vec3(5, 5, 5));
  m.normals.insert(m.normals.end(), 3, glm::vec3(0, 0, 1));
  m.indices.insert(m.indices.end(), {a, a + 1, a + 2});
  MeshSource::MorphTarget t;
  t.positions.assign(m.positions.size(), glm::vec3(0.0f));
  t.positions[a + 1] = {1, 0, 0};
  t.positions[a + 2] = {0, 1, 0};
  m.morphTargets.push_back(t);
  Result<Mesh> built = buildMesh(m);
  ASSERT_TRUE(built.ok()) << built.error().message;
  EXPECT_EQ(built->lods[0].indexCount, 9u * 3);
}

// Levels of many chunks (kClusterChunkTriangles) given in random order: meshlet order keeps every triangle with its
// winding, every cluster but the last is full, and the clusters are tight (the chunks are spatial).
TEST(Clusters, ChunkedMeshletOrderKeepsTrianglesAndStaysTight) {
  Result<Mesh> mesh = buildMesh(makeTorusKnot(256, 48));
  ASSERT_TRUE(mesh.ok());
  const Lod& lod = mesh->lods[0];
  ASSERT_GT(lod.indexCount / 3, 3 * kClusterChunkTriangles);
  const auto before = trianglesAt(*mesh, 0);
  std::vector<std::array<uint32_t, 3>> tris;
  for (uint32_t i = 0; i < lod.indexCount; i += 3)
    tris.push_back({mesh->indices[lod.firstIndex + i], mesh->indices[lod.firstIndex + i + 1],
                    mesh->indices[lod.firstIndex + i + 2]});
  std::shuffle(tris.begin(), tris.end(), std::mt19937(3));
  Mesh shuffled = *mesh;
  for (size_t t = 0; t < tris.size(); ++t) std::copy(tris[t].begin(), tris[t].end(), &shuffled.indices[lod.firstIndex + 3 * t]);
  Mesh ordered = shuffled;
  clusterOrder(&ordered.indices[lod.firstIndex], lod.indexCount, &ordered.vertices[0].px, ordered.vertices.size(),
               sizeof(gpu::Vertex));
  EXPECT_EQ(trianglesAt(ordered, 0), before);
  auto meanRadius = [](const Mesh& m) {
    double sum = 0.0;
    const std::vector<gpu::ClusterData> c = lodClusters(m, 0);
    for (const gpu::ClusterData& d : c) sum += d.sphere.w;
    return sum / double(c.size());
  };
  EXPECT_LT(meanRadius(ordered), 0.25 * meanRadius(shuffled));
  // Within 25% of one meshopt_buildMeshlets pass over the whole level (the reference the chunks bound): chunk borders
  // cost little.
  Mesh single = shuffled;
  {
    const size_t n = lod.indexCount;
    const size_t bound = meshopt_buildMeshletsBound(n, 3 * CLUSTER_TRIANGLES, CLUSTER_TRIANGLES);
    std::vector<meshopt_Meshlet> ml(bound);
    std::vector<uint32_t> mv(bound * 3 * CLUSTER_TRIANGLES);
    std::vector<unsigned char> mt(bound * CLUSTER_TRIANGLES * 3);
    const size_t count = meshopt_buildMeshlets(ml.data(), mv.data(), mt.data(), &shuffled.indices[lod.firstIndex], n,
                                               &shuffled.vertices[0].px, shuffled.vertices.size(), sizeof(gpu::Vertex),
                                               3 * CLUSTER_TRIANGLES, CLUSTER_TRIANGLES, 0.5f);
    size_t at = lod.firstIndex;
    for (size_t m = 0; m < count; ++m)
      for (uint32_t k = 0; k < ml[m].triangle_count * 3; ++k)
        single.indices[at++] = mv[ml[m].vertex_offset + mt[ml[m].triangle_offset + k]];
    ASSERT_EQ(at, lod.firstIndex + n);
  }
  EXPECT_LT(meanRadius(ordered), 1.25 * meanRadius(single));
}

// A fan (one vertex in every triangle) and stacked copies build, with every kept triangle in LOD0.
TEST(MeshBuild, FanAndStackedCopiesBuild) {
  Result<Mesh> f = buildMesh(sourceOf(fan(20000)));
  ASSERT_TRUE(f.ok()) << f.error().message;
  EXPECT_EQ(f->lods[0].indexCount, 20000u * 3);
  Result<Mesh> st = buildMesh(sourceOf(stacked(20000)));
  ASSERT_TRUE(st.ok()) << st.error().message;
  // Copies at the same places cover the same pixels at the same depths: one is kept.
  EXPECT_EQ(st->vertices.size(), 3u);
  EXPECT_EQ(st->lods[0].indexCount, 3u);
}

// Repeated triangles: copies with their own vertices and normals collapse to the first; the reversed winding (a
// back face) stays, and so does a copy that a morph target moves elsewhere.
TEST(MeshBuild, DropsRepeatedTrianglesOnlyWhereNoPoseSeparatesThem) {
  MeshSource m = sourceOf(stacked(50));
  for (size_t v = 0; v < m.normals.size(); ++v) m.normals[v] = glm::normalize(glm::vec3(0.01f * float(v), 0, 1));
  const uint32_t n = uint32_t(m.positions.size());
  m.positions.insert(m.positions.end(), {{-100, -100, 0}, {0, 100, 0}, {100, -100, 0}});  // reversed winding
  m.normals.insert(m.normals.end(), 3, glm::vec3(0, 0, -1));
  m.indices.insert(m.indices.end(), {n, n + 1, n + 2});
  Result<Mesh> built = buildMesh(m);
  ASSERT_TRUE(built.ok()) << built.error().message;
  EXPECT_EQ(built->lods[0].indexCount, 2u * 3);
  MeshSource::MorphTarget t;
  t.positions.assign(m.positions.size(), glm::vec3(0.0f));
  t.positions[3] = {0, 0, 1};  // the second copy's first corner moves under the target
  m.morphTargets.push_back(t);
  built = buildMesh(m);
  ASSERT_TRUE(built.ok()) << built.error().message;
  EXPECT_EQ(built->lods[0].indexCount, 3u * 3);
}
