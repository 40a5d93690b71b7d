// The pack reader against a pack that another program changes while it is read (every read is an error or one
// whole version), and the load-time probe of readPack against a mapping (disabled: not a check).
#include "pack_test_util.h"

#include <fcntl.h>
#include <unistd.h>

#include "visbuf/core/mapped_file.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <thread>

namespace visbuf {
namespace {

using namespace pack_test;

// ---- a pack changed by another program while it is read ----------------------------------------------------

class PackReadWhileChanging : public test::TempDirTest {
 protected:
  // A pack of about 11 MB (a 1024 x 1024 texture class, two layers, with mips), so that a read takes long enough
  // for the writer thread to land inside it.
  static Scene largeScene(uint8_t texelXor) {
    Scene scene = makeTexturedTestScene();
    TextureClass& c = scene.textureClasses[0];
    c.size = 1024;
    c.mipCount = TextureClass::mipCountFor(c.size);
    c.texels.resize(c.totalBytes());
    for (size_t i = 0; i < c.texels.size(); ++i) c.texels[i] = uint8_t((i * 7 + (i >> 12)) ^ texelXor);
    return scene;
  }
};

// Two packs of the same layout and size that differ only in their texels (each valid, its checksums sealed);
// another thread writes one, then the other, over the file in place while readPack reads it again and again.
// Every read is an error or exactly one of the two scenes: never texels written after the checksum was checked.
TEST_F(PackReadWhileChanging, InPlaceOverwriteIsAnErrorOrOneWholeVersion) {
  const Scene a = largeScene(0), b = largeScene(0x5a);
  PackWriteOptions raw;  // compressed, the two texel patterns would give packs of different sizes
  raw.compressionLevel = 0;
  Result<std::vector<uint8_t>> bytesA = serializePack(a, raw), bytesB = serializePack(b, raw);
  ASSERT_TRUE(bytesA && bytesB);
  ASSERT_EQ(bytesA->size(), bytesB->size());
  const std::string path = (dir_ / "changing.vbp").string();
  { std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytesA->data()), bytesA->size()); }
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> writes{0};
  std::thread writer([&] {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    for (bool flip = true; fd >= 0 && !stop.load(); flip = !flip) {
      const std::vector<uint8_t>& v = flip ? *bytesB : *bytesA;
      // In 64 KiB pieces, as a program writing a file does: a read sees the file half old, half new.
      for (size_t at = 0; at < v.size() && !stop.load(); at += 65536)
        if (::pwrite(fd, v.data() + at, std::min<size_t>(65536, v.size() - at), off_t(at)) < 0) break;
      ++writes;
    }
    if (fd >= 0) ::close(fd);
  });
  size_t errors = 0, asA = 0, asB = 0;
  constexpr int kReads = 60;
  for (int i = 0; i < kReads; ++i) {
    Result<Scene> r = readPack(path);
    if (!r) {
      EXPECT_TRUE(r.error().code == ErrorCode::IoError || r.error().code == ErrorCode::MalformedInput)
          << r.error().message;
      ++errors;
    } else if (r->textureClasses == a.textureClasses) {
      ++asA;
    } else if (r->textureClasses == b.textureClasses) {
      ++asB;
    } else {
      ADD_FAILURE() << "read " << i << ": texels of neither version (changed after the checksum check)";
    }
  }
  stop = true;
  writer.join();
  EXPECT_GT(writes.load(), 0u);
  std::printf("[          ] %d reads: %zu errors, %zu version A, %zu version B, %llu writes\n", kReads, errors, asA,
              asB, static_cast<unsigned long long>(writes.load()));
}

// Another thread truncates the file in place and writes it back whole, again and again: every read is an error
// (shrank, changed, truncated, checksum) or the whole scene, never SIGBUS (which would end this test program).
TEST_F(PackReadWhileChanging, InPlaceTruncationIsAnErrorNeverASignal) {
  const Scene a = largeScene(0);
  Result<std::vector<uint8_t>> bytes = serializePack(a);
  ASSERT_TRUE(bytes);
  const std::string path = (dir_ / "shrinking.vbp").string();
  { std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes->data()), bytes->size()); }
  std::atomic<bool> stop{false};
  std::thread writer([&] {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    for (size_t k = 1; fd >= 0 && !stop.load(); k = k % 7 + 1) {
      if (::ftruncate(fd, off_t(bytes->size() * k / 8)) != 0) break;
      if (::pwrite(fd, bytes->data(), bytes->size(), 0) < 0) break;
    }
    if (fd >= 0) ::close(fd);
  });
  size_t errors = 0, whole = 0;
  for (int i = 0; i < 60; ++i) {
    Result<Scene> r = readPack(path);
    if (!r) {
      EXPECT_TRUE(r.error().code == ErrorCode::IoError || r.error().code == ErrorCode::MalformedInput)
          << r.error().message;
      ++errors;
    } else {
      EXPECT_EQ(r->textureClasses, a.textureClasses) << "read " << i;
      ++whole;
    }
  }
  stop = true;
  writer.join();
  std::printf("[          ] 60 reads: %zu errors, %zu whole\n", errors, whole);
}

// Not a check: the load time of the pack named by VISBUF_PACK, read as readPack does (once into private memory,
// then parsed) against a read-only mapping parsed in place (MappedFile: how packs were read before), interleaved,
// page cache warm, medians of 7. Run with --gtest_also_run_disabled_tests --gtest_filter='*PackLoadTime*'.
TEST(PackReaderTiming, DISABLED_PackLoadTime) {
  const char* path = std::getenv("VISBUF_PACK");
  if (path == nullptr) GTEST_SKIP() << "set VISBUF_PACK to a pack file";
  std::vector<double> copied, mapped, readOnly;
  for (int i = 0; i < 8; ++i) {
    auto tr = std::chrono::steady_clock::now();
    {
      Result<FileSnapshot> snapshot = readFileSnapshot(path, {.maxBytes = kMaxPackFileBytes});
      ASSERT_TRUE(snapshot);
    }
    auto t0 = std::chrono::steady_clock::now();
    Result<Scene> a = readPack(path);
    auto t1 = std::chrono::steady_clock::now();
    Result<MappedFile> file = MappedFile::open(path, {.maxBytes = kMaxPackFileBytes});
    ASSERT_TRUE(file);
    Result<Scene> b = parsePack(file->data(), file->size(), path);
    file->reset();
    auto t2 = std::chrono::steady_clock::now();
    ASSERT_TRUE(a && b) << (a ? b.error().message : a.error().message);
    if (i == 0) continue;  // warms the page cache
    copied.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    readOnly.push_back(std::chrono::duration<double, std::milli>(t0 - tr).count());
    mapped.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
  }
  std::sort(copied.begin(), copied.end());
  std::sort(readOnly.begin(), readOnly.end());
  std::sort(mapped.begin(), mapped.end());
  std::printf("[          ] %s: readPack (private copy) %.2f ms, of which the read alone %.2f ms; mapping parsed in "
              "place %.2f ms (medians of %zu)\n",
              path, copied[copied.size() / 2], readOnly[readOnly.size() / 2], mapped[mapped.size() / 2], copied.size());
}

}  // namespace
}  // namespace visbuf
