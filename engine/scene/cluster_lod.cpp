#include "visbuf/scene/cluster_lod.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <meshoptimizer.h>

#include "cluster_lod_groups.h"
#include "visbuf/scene/clusters.h"
#include "visbuf/scene/mesh_error.h"

namespace visbuf {

namespace {

using cluster_lod_detail::GroupInput;

// A sphere containing every sphere of `spheres` (not the smallest: grown one sphere at a time, largest first), its
// radius then set to the farthest reach of any of them from the float centre in double and padded, so that the float
// sphere contains each of them exactly and with a margin (1e-5 relative) against the float rounding of a distance
// computed from it (the selection's monotonicity needs the parent's projected error not to fall below a child's).
glm::vec4 enclosingSphere(const std::vector<glm::vec4>& spheres) {
  std::vector<glm::vec4> order = spheres;
  std::sort(order.begin(), order.end(), [](const glm::vec4& a, const glm::vec4& b) { return a.w > b.w; });
  glm::dvec3 c(order[0]);
  double r = order[0].w;
  for (const glm::vec4& s : order) {
    const glm::dvec3 d = glm::dvec3(s) - c;
    const double dist = glm::length(d);
    if (dist + s.w <= r) continue;
    if (dist + r <= s.w) {
      c = glm::dvec3(s);
      r = s.w;
      continue;
    }
    const double grown = 0.5 * (dist + r + s.w);
    c += d * ((grown - r) / dist);
    r = grown;
  }
  const glm::vec3 centre(c);
  double reach = 0.0;
  for (const glm::vec4& s : spheres) reach = std::max(reach, glm::length(glm::dvec3(s) - glm::dvec3(centre)) + s.w);
  return glm::vec4(centre, float(reach * (1.0 + 1e-5) + 1e-6));
}

// The builder's state: the input, the hierarchy being built and reusable scratch.
class Builder {
 public:
  Builder(const float* positions, size_t vertexCount, size_t stride, const ClusterLodOptions& options)
      : positions_(positions), vertexCount_(vertexCount), floatStride_(stride / sizeof(float)), options_(options),
        localOf_(vertexCount, ~0u) {}

  glm::vec3 position(uint32_t v) const {
    const float* p = positions_ + size_t(v) * floatStride_;
    return {p[0], p[1], p[2]};
  }

  // Position ids: vertices at the same place get the same id (the grouping's edges are those of the surface).
  void weld() {
    // (meshoptimizer takes whole triangles: the identity list is padded to a multiple of 3 with vertex 0.)
    std::vector<uint32_t> identity((vertexCount_ + 2) / 3 * 3, 0);
    for (uint32_t v = 0; v < vertexCount_; ++v) identity[v] = v;
    weld_.resize(identity.size());
    meshopt_generateShadowIndexBuffer(weld_.data(), identity.data(), identity.size(), positions_, vertexCount_,
                                      sizeof(float) * 3, floatStride_ * sizeof(float));
    weld_.resize(vertexCount_);
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t v = 0; v < vertexCount_; ++v) {
      lo = glm::min(lo, position(uint32_t(v)));
      hi = glm::max(hi, position(uint32_t(v)));
    }
    // A group's error is at least this (1e-7 of the mesh's size): never 0, so threshold 0 keeps level 0 everywhere.
    minError_ = std::max(glm::length(hi - lo) * 1e-7f, FLT_MIN);
  }

  // Splits `indices` (global vertex ids, in `scratch` order) into clusters of at most CLUSTER_TRIANGLES triangles
  // (clusterOrder's meshlets) and appends them at `level` with `self` bounds; returns their positions.
  std::vector<uint32_t> addClusters(std::vector<uint32_t>& indices, uint32_t level, const ClusterLodBounds& self,
                                    uint32_t sourceGroup) {
    std::vector<uint32_t> made;
    for (size_t first = 0; first < indices.size(); first += 3 * CLUSTER_TRIANGLES) {
      const size_t n = std::min(indices.size() - first, size_t(3 * CLUSTER_TRIANGLES));
      ClusterLodCluster c;
      c.firstIndex = uint32_t(lod_.indices.size());
      c.triangleCount = uint32_t(n / 3);
      c.level = level;
      c.sphere = clusterBounds(indices.data() + first, n, positions_, vertexCount_, floatStride_ * sizeof(float)).sphere;
      c.self = self;
      if (level == 0) c.self.sphere = c.sphere;
      c.parent.error = INFINITY;
      c.sourceGroup = sourceGroup;
      lod_.indices.insert(lod_.indices.end(), indices.begin() + std::ptrdiff_t(first),
                          indices.begin() + std::ptrdiff_t(first + n));
      made.push_back(uint32_t(lod_.clusters.size()));
      lod_.clusters.push_back(c);
      lod_.levels = std::max(lod_.levels, level + 1);
    }
    return made;
  }

  // Level 0: the input triangles in meshlet order (as given with options.inputInClusterOrder).
  std::vector<uint32_t> addInput(const uint32_t* indices, size_t indexCount) {
    std::vector<uint32_t> all(indices, indices + indexCount);
    if (!options_.inputInClusterOrder)
      clusterOrder(all.data(), all.size(), positions_, vertexCount_, floatStride_ * sizeof(float));
    return addClusters(all, 0, {}, ~0u);
  }

  // Merges the clusters of `group`, simplifies them with the group's border locked and splits the result into new
  // clusters (appended to `made`). False, with nothing changed, when the simplification does not make progress.
  bool simplifyGroup(const std::vector<uint32_t>& group, std::vector<uint32_t>& made) {
    // The group on its own vertices (meshoptimizer's cost then follows the group, not the mesh).
    merged_.clear();
    globalOf_.clear();
    localPositions_.clear();
    for (uint32_t c : group) {
      const ClusterLodCluster& cl = lod_.clusters[c];
      for (uint32_t i = cl.firstIndex; i < cl.firstIndex + 3 * cl.triangleCount; ++i) {
        const uint32_t v = lod_.indices[i];
        if (localOf_[v] == ~0u) {
          localOf_[v] = uint32_t(globalOf_.size());
          globalOf_.push_back(v);
          localPositions_.push_back(position(v));
        }
        merged_.push_back(localOf_[v]);
      }
    }
    for (uint32_t v : globalOf_) localOf_[v] = ~0u;
    const size_t target = size_t(double(merged_.size() / 3) * options_.simplifyRatio) * 3;
    simplified_.resize(merged_.size());
    float relative = 0.0f;
    const size_t count = meshopt_simplify(simplified_.data(), merged_.data(), merged_.size(), &localPositions_[0].x,
                                          localPositions_.size(), sizeof(glm::vec3), target, FLT_MAX,
                                          meshopt_SimplifyLockBorder, &relative);
    if (count == 0 || double(count) > double(merged_.size()) * options_.minReduction) return false;
    simplified_.resize(count);
    // Error: the children's (the largest) plus this step's measured deviation from their surface (never below
    // meshoptimizer's own estimate), raised by 2^-10 over the children's so that float rounding of the projected
    // errors cannot reorder a parent below its child; at least minError_.
    float childError = 0.0f;
    std::vector<glm::vec4> spheres;
    for (uint32_t c : group) {
      childError = std::max(childError, lod_.clusters[c].self.error);
      spheres.push_back(lod_.clusters[c].self.sphere);
    }
    const double step = std::max(measureSimplificationError(localPositions_, merged_, simplified_),
                                 double(relative) * meshopt_simplifyScale(&localPositions_[0].x, localPositions_.size(),
                                                                          sizeof(glm::vec3)));
    ClusterLodGroup g;
    g.bounds.error = std::max(float(double(childError) * (1.0 + 0x1.0p-10) + step), minError_);
    g.bounds.sphere = enclosingSphere(spheres);
    for (uint32_t c : group) g.level = std::max(g.level, lod_.clusters[c].level);
    const uint32_t id = uint32_t(lod_.groups.size());
    lod_.groups.push_back(g);
    for (uint32_t c : group) {
      lod_.clusters[c].parent = g.bounds;
      lod_.clusters[c].group = id;
    }
    clusterOrder(simplified_.data(), count, &localPositions_[0].x, localPositions_.size(), sizeof(glm::vec3));
    for (uint32_t& i : simplified_) i = globalOf_[i];
    const std::vector<uint32_t> added = addClusters(simplified_, g.level + 1, g.bounds, id);
    made.insert(made.end(), added.begin(), added.end());
    return true;
  }

  // One round: groups the pending clusters and simplifies each group. Returns the clusters pending after it (the
  // new ones and those of groups that made no progress); `progress` tells whether any group was simplified.
  std::vector<uint32_t> round(const std::vector<uint32_t>& pending, bool& progress) {
    std::vector<uint32_t> welded;
    std::vector<GroupInput> inputs(pending.size());
    std::vector<size_t> offset(pending.size() + 1, 0);
    for (size_t i = 0; i < pending.size(); ++i) offset[i + 1] = offset[i] + 3 * lod_.clusters[pending[i]].triangleCount;
    welded.resize(offset.back());
    for (size_t i = 0; i < pending.size(); ++i) {
      const ClusterLodCluster& c = lod_.clusters[pending[i]];
      for (size_t k = 0; k < 3 * c.triangleCount; ++k) welded[offset[i] + k] = weld_[lod_.indices[c.firstIndex + k]];
      inputs[i].weldedIndices = std::span<const uint32_t>(welded.data() + offset[i], 3 * c.triangleCount);
      inputs[i].centre = glm::vec3(c.sphere);
    }
    std::vector<uint32_t> next;
    progress = false;
    for (const std::vector<uint32_t>& members : cluster_lod_detail::groupClusters(inputs, options_.groupSize)) {
      std::vector<uint32_t> group;
      for (uint32_t m : members) group.push_back(pending[m]);
      if (simplifyGroup(group, next))
        progress = true;
      else
        next.insert(next.end(), group.begin(), group.end());
    }
    std::sort(next.begin(), next.end());
    return next;
  }

  ClusterLod take() { return std::move(lod_); }

 private:
  const float* positions_;
  size_t vertexCount_;
  size_t floatStride_;
  ClusterLodOptions options_;
  ClusterLod lod_;
  std::vector<uint32_t> weld_;
  float minError_ = FLT_MIN;
  // simplifyGroup's scratch: localOf_ is ~0u everywhere between calls.
  std::vector<uint32_t> localOf_, globalOf_, merged_, simplified_;
  std::vector<glm::vec3> localPositions_;
};

}  // namespace

Result<ClusterLod> buildClusterLod(const float* positions, size_t vertexCount, size_t stride, const uint32_t* indices,
                                   size_t indexCount, const ClusterLodOptions& options) {
  if (indexCount == 0 || indexCount % 3 != 0)
    return makeError(ErrorCode::MalformedInput,
                     fmt::format("cluster LOD: {} indices (need a positive multiple of 3)", indexCount));
  if (indexCount > std::numeric_limits<uint32_t>::max() / 2)  // every level's indices together stay 32-bit
    return makeError(ErrorCode::CapacityExceeded, fmt::format("cluster LOD: {} indices (at most 2^31 - 1)", indexCount));
  if (vertexCount == 0 || vertexCount > std::numeric_limits<uint32_t>::max() || stride < 3 * sizeof(float) ||
      stride % sizeof(float) != 0)
    return makeError(ErrorCode::MalformedInput,
                     fmt::format("cluster LOD: {} vertices of stride {} bytes", vertexCount, stride));
  for (size_t i = 0; i < indexCount; ++i)
    if (indices[i] >= vertexCount)
      return makeError(ErrorCode::MalformedInput,
                       fmt::format("cluster LOD: index {} is {} ({} vertices)", i, indices[i], vertexCount));
  for (size_t v = 0; v < vertexCount; ++v) {
    const float* p = positions + v * (stride / sizeof(float));
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      return makeError(ErrorCode::MalformedInput, fmt::format("cluster LOD: vertex {} has a non-finite position", v));
  }
  if (options.groupSize < 2 || !(options.simplifyRatio > 0.0f && options.simplifyRatio < 1.0f) ||
      !(options.minReduction > 0.0f && options.minReduction < 1.0f))
    return makeError(ErrorCode::InvalidArgument, "cluster LOD: groupSize >= 2, simplifyRatio and minReduction in (0, 1)");
  Builder b(positions, vertexCount, stride, options);
  b.weld();
  std::vector<uint32_t> pending = b.addInput(indices, indexCount);
  for (uint32_t level = 1; level < kClusterLodMaxLevels && pending.size() > 1; ++level) {
    bool progress = false;
    pending = b.round(pending, progress);
    if (!progress) break;
  }
  return b.take();
}

float projectedError(const ClusterLodBounds& bounds, const ClusterLodView& view) {
  const float distance = glm::length(glm::vec3(bounds.sphere) - view.camera) - bounds.sphere.w;
  return bounds.error * view.projectionScale / std::max(distance, view.minDistance);
}

std::vector<uint32_t> selectClusters(const ClusterLod& lod, const ClusterLodView& view) {
  std::vector<uint32_t> out;
  for (uint32_t c = 0; c < lod.clusters.size(); ++c) {
    const ClusterLodCluster& cl = lod.clusters[c];
    if (projectedError(cl.self, view) <= view.thresholdPixels && view.thresholdPixels < projectedError(cl.parent, view))
      out.push_back(c);
  }
  return out;
}

}  // namespace visbuf
