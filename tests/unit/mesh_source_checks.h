// Checks on an imported MeshSource shared by the glTF import tests (test_gltf_import.cpp, test_gltf_import_assets.cpp).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>

#include "visbuf/asset/gltf_import.h"

namespace visbuf::test {

inline glm::vec3 geometricNormal(const MeshSource& m, size_t triangle) {
  const glm::vec3 a = m.positions[m.indices[3 * triangle]];
  const glm::vec3 b = m.positions[m.indices[3 * triangle + 1]];
  const glm::vec3 c = m.positions[m.indices[3 * triangle + 2]];
  return glm::normalize(glm::cross(b - a, c - a));
}

inline void expectVec3Near(const glm::vec3& actual, const glm::vec3& expected, float tolerance = 1e-5f) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

// Invariants every successful import must satisfy (the MeshSource contract).
inline void expectValidMesh(const MeshSource& m) {
  ASSERT_EQ(m.normals.size(), m.positions.size());
  ASSERT_TRUE(m.uvs.empty() || m.uvs.size() == m.positions.size());
  ASSERT_TRUE(m.colors.empty() || m.colors.size() == m.positions.size());
  ASSERT_EQ(m.indices.size() % 3, 0u);
  ASSERT_FALSE(m.indices.empty());
  for (uint32_t index : m.indices) ASSERT_LT(index, m.positions.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    ASSERT_TRUE(std::isfinite(m.positions[i].x) && std::isfinite(m.positions[i].y) &&
                std::isfinite(m.positions[i].z));
    ASSERT_NEAR(glm::length(m.normals[i]), 1.0f, 1e-4f) << "vertex " << i;
  }
}

}  // namespace visbuf::test
