#include "cluster_lod_groups.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <metis.h>

#include "visbuf/scene/clusters.h"

namespace visbuf::cluster_lod_detail {

namespace {

// An edge of the welded mesh, its two vertex ids in order, as one key.
uint64_t edgeKey(uint32_t a, uint32_t b) { return a < b ? uint64_t(a) << 32 | b : uint64_t(b) << 32 | a; }

// Weighted adjacency of the clusters (CSR, symmetric, no self loops): clusters i and j are neighbours when an edge
// on the outline of both (used by one triangle of each) is shared; the weight counts such edges. An edge on the
// outline of more than kMaxSharers clusters (non-manifold input) links only its first kMaxSharers.
struct Adjacency {
  std::vector<uint32_t> start;  // clusters + 1
  std::vector<uint32_t> neighbour;
  std::vector<uint32_t> weight;
};

Adjacency adjacency(std::span<const GroupInput> clusters) {
  constexpr size_t kMaxSharers = 8;
  std::vector<std::pair<uint64_t, uint32_t>> outline;  // (edge, cluster)
  std::vector<uint64_t> edges;
  for (uint32_t c = 0; c < clusters.size(); ++c) {
    const std::span<const uint32_t> idx = clusters[c].weldedIndices;
    edges.clear();
    for (size_t t = 0; t + 2 < idx.size(); t += 3)
      for (int k = 0; k < 3; ++k)
        if (idx[t + k] != idx[t + (k + 1) % 3]) edges.push_back(edgeKey(idx[t + k], idx[t + (k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
      size_t j = i;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i == 1) outline.push_back({edges[i], c});
      i = j;
    }
  }
  std::sort(outline.begin(), outline.end());
  std::vector<std::pair<uint32_t, uint32_t>> pairs;  // both directions
  for (size_t i = 0; i < outline.size();) {
    size_t j = i;
    while (j < outline.size() && outline[j].first == outline[i].first) ++j;
    const size_t end = std::min(j, i + kMaxSharers);
    for (size_t a = i; a < end; ++a)
      for (size_t b = a + 1; b < end; ++b)
        if (outline[a].second != outline[b].second) {
          pairs.push_back({outline[a].second, outline[b].second});
          pairs.push_back({outline[b].second, outline[a].second});
        }
    i = j;
  }
  std::sort(pairs.begin(), pairs.end());
  Adjacency g;
  g.start.assign(clusters.size() + 1, 0);
  for (size_t i = 0; i < pairs.size();) {
    size_t j = i;
    while (j < pairs.size() && pairs[j] == pairs[i]) ++j;
    g.neighbour.push_back(pairs[i].second);
    g.weight.push_back(uint32_t(j - i));
    g.start[pairs[i].first + 1]++;
    i = j;
  }
  for (size_t c = 0; c < clusters.size(); ++c) g.start[c + 1] += g.start[c];
  return g;
}

// The clusters in Morton order of their centres (over the centres' box).
std::vector<uint32_t> mortonOrder(std::span<const GroupInput> clusters) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const GroupInput& c : clusters) {
    lo = glm::min(lo, glm::dvec3(c.centre));
    hi = glm::max(hi, glm::dvec3(c.centre));
  }
  const glm::dvec3 scale = 2097151.0 / glm::max(hi - lo, glm::dvec3(1e-30));
  std::vector<std::pair<uint64_t, uint32_t>> keys(clusters.size());
  for (uint32_t i = 0; i < clusters.size(); ++i) {
    const glm::dvec3 q = glm::clamp((glm::dvec3(clusters[i].centre) - lo) * scale, glm::dvec3(0.0), glm::dvec3(2097151.0));
    keys[i] = {spreadBits3(uint64_t(q.x)) | spreadBits3(uint64_t(q.y)) << 1 | spreadBits3(uint64_t(q.z)) << 2, i};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(clusters.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = keys[i].second;
  return order;
}

// METIS k-way on the clusters `members` (positions into the adjacency), parts of about groupSize; false when METIS
// fails. part[i] is member i's part. `local` (one entry per cluster) is ~0u everywhere on entry and on return.
bool partition(const Adjacency& g, std::span<const GroupInput> clusters, std::span<const uint32_t> members,
               uint32_t groupSize, std::vector<uint32_t>& local, std::vector<idx_t>& part) {
  idx_t n = idx_t(members.size());
  idx_t parts = idx_t((members.size() + groupSize - 1) / groupSize);
  part.assign(members.size(), 0);
  if (parts <= 1) return true;
  for (uint32_t i = 0; i < members.size(); ++i) local[members[i]] = i;
  std::vector<idx_t> xadj{0}, adjncy, adjwgt, vwgt;
  for (uint32_t m : members) {
    for (uint32_t e = g.start[m]; e < g.start[m + 1]; ++e)
      if (local[g.neighbour[e]] != ~0u) {
        adjncy.push_back(idx_t(local[g.neighbour[e]]));
        adjwgt.push_back(idx_t(g.weight[e]));
      }
    xadj.push_back(idx_t(adjncy.size()));
    vwgt.push_back(idx_t(std::max<size_t>(clusters[m].weldedIndices.size() / 3, 1)));
  }
  for (uint32_t m : members) local[m] = ~0u;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;
  options[METIS_OPTION_NUMBERING] = 0;
  idx_t ncon = 1, edgecut = 0;
  const int rc = METIS_PartGraphKway(&n, &ncon, xadj.data(), adjncy.empty() ? nullptr : adjncy.data(), vwgt.data(),
                                     nullptr, adjncy.empty() ? nullptr : adjwgt.data(), &parts, nullptr, nullptr,
                                     options, &edgecut, part.data());
  if (rc != METIS_OK) return false;
  for (idx_t p : part)
    if (p < 0 || p >= parts) return false;
  return true;
}

}  // namespace

std::vector<std::vector<uint32_t>> groupClusters(std::span<const GroupInput> clusters, uint32_t groupSize) {
  groupSize = std::max(groupSize, 2u);
  std::vector<std::vector<uint32_t>> groups;
  if (clusters.empty()) return groups;
  const Adjacency g = adjacency(clusters);
  const std::vector<uint32_t> order = mortonOrder(clusters);
  // Chunks of equal size (a small last chunk would make small groups).
  const size_t chunks = (order.size() + kGroupChunkClusters - 1) / kGroupChunkClusters;
  std::vector<idx_t> part;
  std::vector<uint32_t> local(clusters.size(), ~0u);
  for (size_t k = 0; k < chunks; ++k) {
    const size_t first = order.size() * k / chunks, last = order.size() * (k + 1) / chunks;
    const std::span<const uint32_t> members(order.data() + first, last - first);
    if (!partition(g, clusters, members, groupSize, local, part))
      for (size_t i = 0; i < members.size(); ++i) part[i] = idx_t(i / groupSize);  // runs along the curve
    const size_t base = groups.size();
    const idx_t parts = *std::max_element(part.begin(), part.end()) + 1;
    groups.resize(base + size_t(parts));
    for (size_t i = 0; i < members.size(); ++i) groups[base + size_t(part[i])].push_back(members[i]);
  }
  groups.erase(std::remove_if(groups.begin(), groups.end(), [](const auto& v) { return v.empty(); }), groups.end());
  return groups;
}

}  // namespace visbuf::cluster_lod_detail
