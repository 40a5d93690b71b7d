// Shared by the libFuzzer targets of tests/fuzz: a contract check that turns a broken promise of the engine
// (a result that is neither a value nor an Error with a message, an index out of range, ...) into a crash that
// libFuzzer reports with the input that caused it.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#define VISBUF_FUZZ_CHECK(cond, what)                                                     \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "fuzz contract violated: %s (%s:%d)\n", what, __FILE__, __LINE__); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)

namespace visbuf::fuzz {

// The path of one file in a private temporary folder (mkdtemp, removed at exit), for targets whose code under test
// reads files: each input is written there (writeInput). Call once per process (LLVMFuzzerInitialize).
inline std::string privateInputPath(const char* folderPrefix, const char* fileName) {
  static std::string dir;
  std::string pattern = (std::filesystem::temp_directory_path() / (std::string(folderPrefix) + "-XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) {
    std::perror("mkdtemp");
    std::abort();
  }
  dir = pattern;
  std::atexit([] {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  });
  return dir + "/" + fileName;
}

// Replaces the file at `path` with `size` bytes; aborts (a harness failure, not a finding) when it cannot.
inline void writeInput(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  const bool ok = f != nullptr && (size == 0 || std::fwrite(data, 1, size, f) == size);
  if (f == nullptr || std::fclose(f) != 0 || !ok) {
    std::perror(path.c_str());
    std::abort();
  }
}

}  // namespace visbuf::fuzz
