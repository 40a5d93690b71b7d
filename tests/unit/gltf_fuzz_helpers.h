// Shared by the two files of the GltfFuzz suite (test_gltf_fuzz.cpp: the mutation fuzzer;
// test_gltf_fuzz_inputs.cpp: its seed files and the minimized regressions): the fixture, a file writer, the seeds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "temp_dir_test.h"

// A named namespace, not an anonymous one: gtest requires every test of a suite to use the same fixture type
// (one per program, not one per file), and the seed builders are defined in test_gltf_fuzz_inputs.cpp.
namespace visbuf::test::gltf_fuzz {

class GltfFuzz : public TempDirTest {};

inline void writeFile(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

// The fuzzer's generated seed files (described in test_gltf_fuzz_inputs.cpp, where they are defined).
std::vector<uint8_t> makeSkinnedGlb();
std::string makeDataUriGltf();

}  // namespace visbuf::test::gltf_fuzz
