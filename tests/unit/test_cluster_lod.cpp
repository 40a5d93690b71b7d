// The cluster LOD hierarchy (scene/cluster_lod.h) against checks that do not trust it: errors and spheres grow up
// the DAG; threshold 0 gives back exactly the input triangles; every cut of a closed mesh is watertight and every
// cut of an open one keeps the input's outline (edges compared by exact position); coarser from farther; hostile
// input fails cleanly or terminates.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "triangle_sets.h"
#include "visbuf/scene/cluster_lod.h"
#include "visbuf/scene/clusters.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;
using visbuf::test::sortedTriangles;

namespace {

ClusterLod build(const MeshSource& m, const ClusterLodOptions& options = {}) {
  Result<ClusterLod> lod = buildClusterLod(&m.positions[0].x, m.positions.size(), sizeof(glm::vec3), m.indices.data(),
                                           m.indices.size(), options);
  EXPECT_TRUE(lod.ok()) << (lod.ok() ? "" : lod.error().message);
  return lod.ok() ? std::move(lod.value()) : ClusterLod{};
}

std::vector<uint32_t> cutIndices(const ClusterLod& lod, const std::vector<uint32_t>& clusters) {
  std::vector<uint32_t> out;
  for (uint32_t c : clusters) {
    const ClusterLodCluster& cl = lod.clusters[c];
    out.insert(out.end(), lod.indices.begin() + cl.firstIndex, lod.indices.begin() + cl.firstIndex + 3 * cl.triangleCount);
  }
  return out;
}

// Each end of an edge named by its exact position (vertices at one place are one end).
using End = std::array<float, 3>;
using Edge = std::pair<End, End>;

// The oriented boundary of the triangles: for each edge, how many more times it is used from a to b than from b to
// a, listed once per unit of that excess in its direction. Empty for a closed oriented surface (every edge as often
// in each direction: no hole, no crack, no flipped triangle); an open one's outline otherwise. (A simplified level
// may join two sheets along one edge, four triangles around it, and stay closed: counted per direction, that is
// no hole.)
std::vector<Edge> outline(const MeshSource& m, const std::vector<uint32_t>& indices) {
  auto key = [&](uint32_t v) { return End{m.positions[v].x, m.positions[v].y, m.positions[v].z}; };
  std::map<Edge, int> net;
  for (size_t t = 0; t + 2 < indices.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      const End a = key(indices[t + k]), b = key(indices[t + (k + 1) % 3]);
      if (a < b) net[{a, b}]++;
      else net[{b, a}]--;
    }
  std::vector<Edge> out;
  for (const auto& [e, n] : net)
    for (int i = 0; i < std::abs(n); ++i) out.push_back(n > 0 ? e : Edge{e.second, e.first});
  std::sort(out.begin(), out.end());
  return out;
}

// Signed volume enclosed by a closed oriented surface (sum of the tetrahedra to the origin): a region drawn twice
// doubles it even where the edges balance.
double volume(const MeshSource& m, const std::vector<uint32_t>& indices) {
  double v = 0.0;
  for (size_t t = 0; t + 2 < indices.size(); t += 3)
    v += glm::dot(glm::dvec3(m.positions[indices[t]]),
                  glm::cross(glm::dvec3(m.positions[indices[t + 1]]), glm::dvec3(m.positions[indices[t + 2]]))) / 6.0;
  return v;
}

ClusterLodView randomView(std::mt19937& rng, float radius) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), log2Threshold(-2.0f, 8.0f), log2Distance(-1.0f, 5.0f);
  glm::vec3 dir(unit(rng), unit(rng), unit(rng));
  if (glm::length(dir) < 1e-3f) dir = {0.0f, 0.0f, 1.0f};
  ClusterLodView v;
  v.camera = glm::normalize(dir) * radius * std::exp2(log2Distance(rng));
  v.projectionScale = 600.0f;
  v.thresholdPixels = std::exp2(log2Threshold(rng));
  return v;
}

// A closed torus (ring radius 1, tube radius 0.45) of 2 x rings x sides triangles, sharing its seam vertices.
MeshSource torus(uint32_t rings, uint32_t sides) {
  MeshSource m;
  for (uint32_t i = 0; i < rings; ++i)
    for (uint32_t j = 0; j < sides; ++j) {
      const double a = 2.0 * M_PI * i / rings, b = 2.0 * M_PI * j / sides, r = 1.0 + 0.45 * std::cos(b);
      m.positions.push_back(glm::vec3(glm::dvec3(r * std::cos(a), 0.45 * std::sin(b), r * std::sin(a))));
      m.normals.push_back(glm::vec3(0.0f, 1.0f, 0.0f));  // (unused here)
    }
  for (uint32_t i = 0; i < rings; ++i)
    for (uint32_t j = 0; j < sides; ++j) {
      const uint32_t a = i * sides + j, b = ((i + 1) % rings) * sides + j;
      const uint32_t c = ((i + 1) % rings) * sides + (j + 1) % sides, d = i * sides + (j + 1) % sides;
      m.indices.insert(m.indices.end(), {a, c, b, a, d, c});
    }
  return m;
}

MeshSource terrainPatch(uint32_t size) {
  Result<MeshSource> m = makeTerrainMesh({.size = size, .seed = 1});
  EXPECT_TRUE(m.ok());
  return m.ok() ? std::move(m.value()) : MeshSource{};
}

double distance(const glm::vec4& a, const glm::vec4& b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

}  // namespace

TEST(ClusterLod, ErrorsAndSpheresGrowUpTheDag) {
  const MeshSource knot = makeTorusKnot(120, 24);
  const ClusterLod lod = build(knot);
  ASSERT_FALSE(lod.clusters.empty());
  EXPECT_GE(lod.levels, 4u) << "the knot's 5,760 triangles (90 clusters) simplify over several levels";
  size_t roots = 0, roundTrip = 0;
  for (const ClusterLodCluster& c : lod.clusters) {
    ASSERT_GE(c.triangleCount, 1u);
    ASSERT_LE(c.triangleCount, CLUSTER_TRIANGLES);
    for (uint32_t i = c.firstIndex; i < c.firstIndex + 3 * c.triangleCount; ++i)  // the culling sphere holds them
      EXPECT_LE(glm::length(glm::dvec3(knot.positions[lod.indices[i]]) - glm::dvec3(c.sphere)), double(c.sphere.w));
    if (c.sourceGroup == ~0u) {
      EXPECT_EQ(c.level, 0u);
      EXPECT_EQ(c.self.error, 0.0f);
    } else {
      const ClusterLodGroup& g = lod.groups[c.sourceGroup];
      EXPECT_EQ(c.self.error, g.bounds.error);
      EXPECT_EQ(c.self.sphere, g.bounds.sphere);
      EXPECT_EQ(c.level, g.level + 1);
    }
    if (c.group == ~0u) {
      EXPECT_TRUE(std::isinf(c.parent.error));
      ++roots;
      continue;
    }
    const ClusterLodGroup& p = lod.groups[c.group];
    EXPECT_EQ(c.parent.error, p.bounds.error);
    EXPECT_EQ(c.parent.sphere, p.bounds.sphere);
    EXPECT_GE(p.level, c.level);
    EXPECT_GT(c.parent.error, c.self.error);
    EXPECT_LE(distance(c.self.sphere, c.parent.sphere) + c.self.sphere.w, double(c.parent.sphere.w))
        << "the parent's sphere must contain the child's";
    if (c.sourceGroup != ~0u) ++roundTrip;
  }
  EXPECT_GE(roots, 1u);
  EXPECT_LE(roots, 8u) << "a closed mesh simplifies down to a few clusters";
  EXPECT_GT(roundTrip, 0u) << "some clusters are both made by a group and merged into another";
}

TEST(ClusterLod, ThresholdZeroDrawsExactlyTheInputTriangles) {
  for (const MeshSource& m : {makeTorusKnot(120, 24), terrainPatch(65)}) {
    const ClusterLod lod = build(m);
    const auto input = sortedTriangles(m.indices.data(), m.indices.size());
    std::mt19937 rng(5);
    for (int i = 0; i < 4; ++i) {
      ClusterLodView v = randomView(rng, 1000.0f);
      v.thresholdPixels = 0.0f;
      if (i == 3) v.camera *= 1e4f;  // far away: every projected error is tiny, still not 0
      const std::vector<uint32_t> cut = cutIndices(lod, selectClusters(lod, v));
      EXPECT_EQ(sortedTriangles(cut.data(), cut.size()), input) << m.name << " view " << i;
    }
  }
}

// buildMesh's level 0 is already in meshlet order: kept as given, level-0 cluster k is the cull pass's cluster k.
TEST(ClusterLod, InputInClusterOrderKeepsTheLevelAsGiven) {
  Result<Mesh> mesh = buildMesh(makeTorusKnot(120, 24));
  ASSERT_TRUE(mesh.ok());
  const Lod& l0 = mesh->lods[0];
  Result<ClusterLod> lod = buildClusterLod(&mesh->vertices[0].px, mesh->vertices.size(), sizeof(gpu::Vertex),
                                           mesh->indices.data() + l0.firstIndex, l0.indexCount,
                                           {.inputInClusterOrder = true});
  ASSERT_TRUE(lod.ok());
  const std::vector<gpu::ClusterData> gpuClusters = lodClusters(*mesh, 0);
  std::vector<uint32_t> level0;
  for (uint32_t c = 0; c < lod->clusters.size(); ++c)
    if (lod->clusters[c].level == 0) level0.push_back(c);
  ASSERT_EQ(level0.size(), gpuClusters.size());
  for (uint32_t k = 0; k < level0.size(); ++k) {
    const ClusterLodCluster& c = lod->clusters[level0[k]];
    ASSERT_EQ(c.triangleCount, std::min(CLUSTER_TRIANGLES, l0.indexCount / 3 - k * CLUSTER_TRIANGLES));
    EXPECT_TRUE(std::equal(lod->indices.begin() + c.firstIndex, lod->indices.begin() + c.firstIndex + 3 * c.triangleCount,
                           mesh->indices.begin() + l0.firstIndex + 3 * CLUSTER_TRIANGLES * k))
        << "cluster " << k;
    EXPECT_EQ(c.sphere, gpuClusters[k].sphere);
  }
  EXPECT_GT(lod->levels, 2u);
}

TEST(ClusterLod, EveryCutOfAClosedMeshIsWatertight) {
  const MeshSource ring = torus(96, 48);
  const ClusterLod lod = build(ring);
  const double inputVolume = volume(ring, ring.indices);
  ASSERT_TRUE(outline(ring, ring.indices).empty());
  std::mt19937 rng(11);
  size_t coarser = 0;
  for (int i = 0; i < 24; ++i) {
    const ClusterLodView v = randomView(rng, 1.0f);
    const std::vector<uint32_t> selected = selectClusters(lod, v);
    const std::vector<uint32_t> cut = cutIndices(lod, selected);
    ASSERT_FALSE(cut.empty());
    EXPECT_TRUE(outline(ring, cut).empty()) << "view " << i << ": the cut has holes";
    EXPECT_NEAR(volume(ring, cut) / inputVolume, 1.0, 0.5) << "view " << i << ": a region drawn twice or not at all";
    coarser += cut.size() < ring.indices.size();
  }
  EXPECT_GE(coarser, 12u) << "most views draw a coarser cut than the input";
  // The coarsest cut (roots only) is closed too.
  ClusterLodView far{.camera = {1e6f, 0.0f, 0.0f}, .projectionScale = 600.0f, .thresholdPixels = 1e9f};
  const std::vector<uint32_t> cut = cutIndices(lod, selectClusters(lod, far));
  EXPECT_LT(cut.size(), ring.indices.size() / 8);
  EXPECT_TRUE(outline(ring, cut).empty());
  EXPECT_NEAR(volume(ring, cut) / inputVolume, 1.0, 0.5);
}

TEST(ClusterLod, EveryCutOfATerrainKeepsItsOutline) {
  const MeshSource patch = terrainPatch(65);
  const ClusterLod lod = build(patch);
  const auto expected = outline(patch, patch.indices);
  ASSERT_EQ(expected.size(), 4u * 64u);
  std::mt19937 rng(13);
  size_t coarser = 0;
  for (int i = 0; i < 24; ++i) {
    const ClusterLodView v = randomView(rng, 1000.0f);
    const std::vector<uint32_t> cut = cutIndices(lod, selectClusters(lod, v));
    EXPECT_EQ(outline(patch, cut), expected) << "view " << i;
    coarser += cut.size() < patch.indices.size();
  }
  EXPECT_GE(coarser, 12u);
}

TEST(ClusterLod, FartherDrawsFewerTriangles) {
  const MeshSource patch = terrainPatch(129);
  const ClusterLod lod = build(patch);
  const glm::vec3 dir = glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f));
  size_t previous = SIZE_MAX, first = 0;
  for (float d = 2048.0f; d <= 2048.0f * 512.0f; d *= 2.0f) {
    const ClusterLodView v{.camera = dir * d, .projectionScale = 600.0f, .thresholdPixels = 1.0f};
    const size_t n = cutIndices(lod, selectClusters(lod, v)).size() / 3;
    EXPECT_LE(n, previous) << "at distance " << d;
    if (previous == SIZE_MAX) first = n;
    previous = n;
  }
  EXPECT_LT(previous * 4, first) << "far away the terrain is a fraction of its near cut";
}

TEST(ClusterLod, RefusesMalformedInput) {
  const MeshSource knot = makeTorusKnot(24, 8);
  auto attempt = [](const std::vector<glm::vec3>& p, const std::vector<uint32_t>& i) {
    return buildClusterLod(p.empty() ? nullptr : &p[0].x, p.size(), sizeof(glm::vec3), i.data(), i.size());
  };
  std::vector<glm::vec3> nan = knot.positions;
  nan[5].y = std::nanf("");
  Result<ClusterLod> r = attempt(nan, knot.indices);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("vertex 5"), std::string::npos) << r.error().message;
  std::vector<uint32_t> out = knot.indices;
  out[7] = uint32_t(knot.positions.size());
  EXPECT_FALSE(attempt(knot.positions, out).ok());
  EXPECT_FALSE(attempt(knot.positions, {0, 1}).ok());
  EXPECT_FALSE(attempt(knot.positions, {}).ok());
  EXPECT_FALSE(buildClusterLod(&knot.positions[0].x, knot.positions.size(), sizeof(glm::vec3), knot.indices.data(),
                               knot.indices.size(), {.groupSize = 1})
                   .ok());
}

// Degenerate input the glTF importer may pass on: it builds, ends, and its cuts still cover the input.
TEST(ClusterLod, DegenerateInputTerminates) {
  MeshSource soup;  // 3,000 separate triangles: every vertex on a border, nothing can simplify
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (uint32_t t = 0; t < 3000; ++t)
    for (int k = 0; k < 3; ++k) {
      soup.indices.push_back(uint32_t(soup.positions.size()));
      soup.positions.push_back({u(rng), u(rng), u(rng)});
    }
  MeshSource stack;  // 2,000 triangles at one place, and 2,000 collapsed to a point (zero-area clusters)
  stack.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}};
  for (int t = 0; t < 2000; ++t) stack.indices.insert(stack.indices.end(), {0, 1, 2, 3, 3, 3});
  for (const MeshSource* m : {&soup, &stack}) {
    const auto start = std::chrono::steady_clock::now();
    const ClusterLod lod = build(*m);
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
    EXPECT_LE(lod.levels, kClusterLodMaxLevels);
    const ClusterLodView v{.camera = {100.0f, 0.0f, 0.0f}, .projectionScale = 600.0f, .thresholdPixels = 4.0f};
    const std::vector<uint32_t> cut = cutIndices(lod, selectClusters(lod, v));
    EXPECT_FALSE(cut.empty());
    if (m == &soup) {
      EXPECT_EQ(sortedTriangles(cut.data(), cut.size()), sortedTriangles(m->indices.data(), m->indices.size()));
    }
  }
}

// Figures for the report (not a check): build time, levels and the cut of the terrain's default camera at
// 1280x720, threshold 1 px. Size from VISBUF_TERRAIN_SIZE (default 257). Run with --gtest_also_run_disabled_tests.
TEST(ClusterLod, DISABLED_TerrainFigures) {
  const char* env = std::getenv("VISBUF_TERRAIN_SIZE");
  const TerrainParams params{.size = env ? uint32_t(std::atoi(env)) : 257u};
  const MeshSource m = terrainPatch(params.size);
  const auto start = std::chrono::steady_clock::now();
  const ClusterLod lod = build(m);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<size_t> clusters(lod.levels), triangles(lod.levels), drawn(lod.levels), visible(lod.levels);
  for (const ClusterLodCluster& c : lod.clusters) clusters[c.level]++, triangles[c.level] += c.triangleCount;
  const Camera cam = terrainCamera(params);
  const float height = 720.0f, width = 1280.0f;
  const ClusterLodView v{.camera = glm::vec3(cam.position),
                         .projectionScale = float(height / (2.0 * std::tan(cam.fovY / 2.0))),
                         .thresholdPixels = 1.0f};
  // In the view frustum (its four side planes and the near plane, against each cluster's sphere).
  const glm::vec3 f = glm::normalize(glm::vec3(cam.target - cam.position));
  const glm::vec3 r = glm::normalize(glm::cross(f, glm::vec3(cam.up))), up = glm::cross(r, f);
  const float ty = float(std::tan(cam.fovY / 2.0)), tx = ty * width / height;
  const glm::vec3 planes[] = {glm::normalize(f * tx - r), glm::normalize(f * tx + r), glm::normalize(f * ty - up),
                              glm::normalize(f * ty + up), f};
  for (uint32_t c : selectClusters(lod, v)) {
    const ClusterLodCluster& cl = lod.clusters[c];
    drawn[cl.level] += cl.triangleCount;
    bool inside = true;
    for (const glm::vec3& p : planes) inside = inside && glm::dot(glm::vec3(cl.sphere) - v.camera, p) > -cl.sphere.w;
    if (inside) visible[cl.level] += cl.triangleCount;
  }
  std::printf("terrain %u: %zu triangles, built in %.2f s: %u levels, %zu clusters, %zu groups\n", params.size,
              m.indices.size() / 3, seconds, lod.levels, lod.clusters.size(), lod.groups.size());
  size_t total = 0, totalVisible = 0;
  for (uint32_t l = 0; l < lod.levels; ++l) {
    std::printf("  level %2u: %8zu clusters %10zu triangles; cut at 1 px: %8zu triangles, %8zu in the frustum\n", l,
                clusters[l], triangles[l], drawn[l], visible[l]);
    total += drawn[l];
    totalVisible += visible[l];
  }
  std::printf("  cut: %zu triangles, %zu in the frustum\n", total, totalVisible);
}
