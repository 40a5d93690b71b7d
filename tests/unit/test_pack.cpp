// The pack format (engine/asset/pack_{format,writer,reader}.h): round trips of a generated scene and of real assets,
// memory-mapped reads, atomic writes, and a bounded fuzz run. Hostile packs: test_pack_reader.cpp; quantised packs
// and the encoded geometry streams: test_pack_quantize.cpp.
#include <fcntl.h>
#include <linux/capability.h>
#include <sys/syscall.h>
#include <sys/wait.h>

#include <cerrno>

#include "pack_test_util.h"

namespace visbuf {
namespace {

using namespace pack_test;

TEST(PackFormat, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(pack::crc32("123456789", 9), 0xCBF43926u);  // the CRC-32/ISO-HDLC check value (zlib, PNG)
  EXPECT_EQ(pack::crc32("56789", 5, pack::crc32("1234", 4)), 0xCBF43926u);
  EXPECT_EQ(pack::crc32("", 0), 0u);
}

// --- round trips
// --------------------------------------------------------------------------------------------

TEST(PackRoundTrip, GeneratedSceneInMemory) {
  const Scene scene = makeTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(report.fileBytes, bytes->size());
  EXPECT_EQ(bytes->size() % pack::kAlignment, 0u);
  for (const PackSectionInfo& s : report.sections) EXPECT_EQ(s.offset % pack::kAlignment, 0u) << s.name;
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  // The layout is deterministic: serialising the result again gives the same bytes.
  Result<std::vector<uint8_t>> again = serializePack(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *bytes);
}

TEST(PackRoundTrip, TexturedSceneInMemory) {
  const Scene scene = makeTexturedTestScene();
  PackWriteReport report;
  Result<std::vector<uint8_t>> bytes = serializePack(scene, &report);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(report.sections.size(), 15u + 16u);  // 9 required, meshStreams, tangents, uvs1, 3 texture, 16 animation
  Result<Scene> back = parse(*bytes);
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  Result<std::vector<uint8_t>> again = serializePack(*back);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *bytes);
  // A texture class starts 16-aligned in "texels"; the second one after the first one's bytes.
  const pack::SectionEntry classes = entryOf(*bytes, sectionIndex(*bytes, "textureClasses"));
  pack::TextureClassRecord second;
  std::memcpy(&second, bytes->data() + classes.offset + sizeof(second), sizeof(second));
  EXPECT_EQ(second.firstByte, (scene.textureClasses[0].texels.size() + 15) / 16 * 16);
  // The writer refuses inconsistent texture data.
  Scene broken = scene;
  broken.textureClasses[1].texels.pop_back();
  EXPECT_FALSE(serializePack(broken));
  broken = scene;
  broken.materials[1].baseColorTexture.baked = 2;  // a linear texture in the sRGB base colour slot
  EXPECT_FALSE(serializePack(broken));
}

TEST_F(PackFileTest, GeneratedSceneThroughFile) {
  const Scene scene = makeTestScene();
  const fs::path path = dir_ / "scene.vbp";
  ASSERT_TRUE(writePack(scene, path.string()));
  EXPECT_TRUE(isPackFile(path.string()));
  Result<Scene> back = readPack(path.string());
  ASSERT_TRUE(back) << back.error().message;
  expectScenesEqual(scene, *back);
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});  // no temporary file left behind
}

TEST_F(PackFileTest, RealAssetsThroughFile) {
  // The repository's assets, and DamagedHelmet (five 2048^2 textures) when the extra corpus has it.
  std::vector<fs::path> assets;
  for (const char* relative : {"CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb", "OrientationTest/glTF/OrientationTest.gltf",
                               "AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf", "CesiumMan/glTF/CesiumMan.gltf",
                               "Fox/glTF/Fox.gltf"})
    assets.push_back(assetPath(relative));
  if (auto helmet = test::extraAsset("DamagedHelmet/glTF-Binary/DamagedHelmet.glb")) assets.push_back(*helmet);
  for (const fs::path& asset : assets) {
    SCOPED_TRACE(asset.string());
    REQUIRE_ASSET(asset);
    Result<ImportedScene> imported = importGltfScene(asset.string());
    ASSERT_TRUE(imported) << imported.error().message;
    Result<Scene> scene = buildImportedScene(*imported);
    ASSERT_TRUE(scene) << scene.error().message;
    EXPECT_EQ(scene->objects.size(), imported->instances.size());
    const fs::path path = dir_ / "asset.vbp";
    ASSERT_TRUE(writePack(*scene, path.string()));
    Result<Scene> back = readPack(path.string());
    ASSERT_TRUE(back) << back.error().message;
    expectScenesEqual(*scene, *back);
  }
}

// --- damaged files
// ------------------------------------------------------------------------------------------

TEST_F(PackFileTest, MappedReadMatchesInMemoryParseAndTruncationFailsCleanly) {
  const Scene scene = makeTexturedTestScene();
  const fs::path path = dir_ / "mapped.vbp";
  ASSERT_TRUE(writePack(scene, path.string()));
  const std::vector<uint8_t> bytes = readBytes(path);
  PackReadStats stats;
  Result<Scene> mapped = readPack(path.string(), &stats);
  ASSERT_TRUE(mapped) << mapped.error().message;
  expectScenesEqual(scene, *mapped);
  EXPECT_EQ(stats.fileBytes, bytes.size());
  uint64_t largest = 0;
  for (size_t i = 0; i < headerOf(bytes).sectionCount; ++i) largest = std::max(largest, entryOf(bytes, i).size);
  EXPECT_EQ(stats.largestSection, largest);
  EXPECT_EQ(stats.peakScratchBytes, 0u);  // plain vertices decode straight into the scene
  // Truncated on disk: the size checks against the header come before any section is touched.
  fs::resize_file(path, bytes.size() / 2);
  Result<Scene> cut = readPack(path.string());
  ASSERT_FALSE(cut);
  EXPECT_EQ(cut.error().code, ErrorCode::MalformedInput);
  EXPECT_NE(cut.error().message.find("runs past the end of the file"), std::string::npos) << cut.error().message;
  fs::resize_file(path, 0);
  Result<Scene> empty = readPack(path.string());
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("file is 0 bytes"), std::string::npos) << empty.error().message;
  EXPECT_EQ(readPack((dir_ / "missing.vbp").string()).error().code, ErrorCode::FileNotFound);
  EXPECT_EQ(readPack(dir_.string()).error().code, ErrorCode::InvalidArgument);
  // Quantised: one mesh's 20-byte records are the only decode scratch.
  ASSERT_TRUE(writePack(scene, path.string(), PackWriteOptions{true}));
  ASSERT_TRUE(readPack(path.string(), &stats));
  size_t most = 0;
  for (const Mesh& m : scene.meshes) most = std::max(most, m.vertices.size());
  EXPECT_EQ(stats.peakScratchBytes, most * sizeof(pack::QVertexRecord));
}

// --- atomic writes
// ------------------------------------------------------------------------------------------

TEST_F(PackFileTest, FailedWriteKeepsTheOldPack) {
  const fs::path path = dir_ / "scene.vbp";
  Scene small = makeTestScene(16, 6);
  ASSERT_TRUE(writePack(small, path.string()));
  const std::vector<uint8_t> before = readBytes(path);

  // Simulate a full disk / quota: a file size limit below the new pack's size makes write() fail (EFBIG).
  Scene big = makeTestScene(256, 32);
  struct rlimit old {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  struct sigaction ignore {
  }, previous{};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &previous), 0);
  struct rlimit limited = old;
  limited.rlim_cur = before.size() + 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limited), 0);
  Status s = writePack(big, path.string());
  setrlimit(RLIMIT_FSIZE, &old);
  sigaction(SIGXFSZ, &previous, nullptr);

  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::IoError);
  EXPECT_NE(s.error().message.find("write failed"), std::string::npos) << s.error().message;
  EXPECT_EQ(readBytes(path), before);                           // the old pack is intact
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});  // and no partial file is left
  EXPECT_TRUE(readPack(path.string()));
}

TEST_F(PackFileTest, DestinationProblemsLeaveNothingBehind) {
  const Scene scene = makeTestScene(16, 6);
  // The destination is a directory: the rename fails, the temporary file is removed.
  fs::create_directories(dir_ / "taken.vbp");
  Status s = writePack(scene, (dir_ / "taken.vbp").string());
  EXPECT_FALSE(s);
  EXPECT_EQ(listing(), std::vector<std::string>{"taken.vbp"});
  EXPECT_TRUE(fs::is_empty(dir_ / "taken.vbp"));
  // The folder does not exist.
  s = writePack(scene, (dir_ / "missing" / "x.vbp").string());
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("cannot create the temporary file"), std::string::npos)
      << s.error().message;
  // A scene that fails validation writes nothing.
  Scene broken = scene;
  broken.objects[0].mesh = 99;
  EXPECT_FALSE(writePack(broken, (dir_ / "broken.vbp").string()));
  EXPECT_EQ(listing(), std::vector<std::string>{"taken.vbp"});
}

// What writePack returned where an ordinary user's permissions held, or why it could not be run there (`setup`).
struct WriteOutcome {
  bool ok = false;
  int code = -1;  // ErrorCode, when !ok
  std::string message;
  std::string setup;  // non-empty: the run did not happen as intended (a failure of the test, never a skip)
};

// Whether a file can be created in `dir` by this thread's credentials (it is removed again).
std::string probeWritable(const fs::path& dir) {
  const fs::path probe = dir / "probe";
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd >= 0) {
    ::close(fd);
    ::unlink(probe.c_str());
    return "a file could still be created in the read-only directory: the test would prove nothing";
  }
  if (errno != EACCES) return std::string("probe: unexpected error ") + std::strerror(errno);
  return {};
}

// writePack(scene, path) with the permissions of an ordinary user. As root (CI's containers run as root), whose
// CAP_DAC_OVERRIDE ignores a directory's mode, a forked child first drops every capability with capset (effective,
// permitted and inheritable sets emptied: it stays uid 0, the directory's owner, and the owner's mode bits then bind
// it), checks that it can no longer create a file there, runs writePack, and reports through a pipe and its exit
// status (_exit: no atexit handlers, no leak check of the copied process). Otherwise writePack runs here, after the
// same check.
WriteOutcome writeAsOrdinaryUser(const Scene& scene, const fs::path& dir, const fs::path& path) {
  WriteOutcome out;
  if (geteuid() != 0) {
    out.setup = probeWritable(dir);
    if (!out.setup.empty()) return out;
    Status s = writePack(scene, path.string());
    out.ok = s.ok();
    if (!s) out.code = int(s.error().code), out.message = s.error().message;
    return out;
  }
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return {false, -1, {}, "pipe failed"};
  const pid_t pid = ::fork();
  if (pid < 0) return {false, -1, {}, "fork failed"};
  if (pid == 0) {
    ::close(fds[0]);
    auto report = [&](const std::string& text, int status) {
      const ssize_t written = ::write(fds[1], text.data(), text.size());
      ::_exit(written == ssize_t(text.size()) ? status : 4);
    };
    __user_cap_header_struct header{_LINUX_CAPABILITY_VERSION_3, 0};
    __user_cap_data_struct none[_LINUX_CAPABILITY_U32S_3] = {};
    if (::syscall(SYS_capset, &header, none) != 0) report(std::string("capset: ") + std::strerror(errno), 2);
    if (std::string probe = probeWritable(dir); !probe.empty()) report(probe, 3);
    Status s = writePack(scene, path.string());
    report(s ? std::string("ok") : std::to_string(int(s.error().code)) + " " + s.error().message, 0);
  }
  ::close(fds[1]);
  std::string text;
  char buffer[512];
  for (ssize_t n; (n = ::read(fds[0], buffer, sizeof(buffer))) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    text.append(buffer, size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    return {false, -1, {}, "the unprivileged child failed (status " + std::to_string(status) + "): " + text};
  if (text == "ok") return {true, -1, {}, {}};
  const size_t space = text.find(' ');
  const std::string message = space == std::string::npos ? std::string() : text.substr(space + 1);
  return {false, std::atoi(text.substr(0, space).c_str()), message, {}};
}

// writePack into a directory it may not write (mode r-x): an IoError, the old pack intact, no temporary file left.
// Run with an ordinary user's permissions also as root (writeAsOrdinaryUser), so it never skips.
TEST_F(PackFileTest, UnwritableDirectory) {
  const fs::path path = dir_ / "scene.vbp";
  ASSERT_TRUE(writePack(makeTestScene(16, 6), path.string()));
  const std::vector<uint8_t> before = readBytes(path);
  const Scene bigger = makeTestScene();
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  const WriteOutcome w = writeAsOrdinaryUser(bigger, dir_, path);
  fs::permissions(dir_, fs::perms::owner_all);
  ASSERT_TRUE(w.setup.empty()) << w.setup;
  ASSERT_FALSE(w.ok) << "writePack succeeded in a read-only directory";
  EXPECT_EQ(w.code, int(ErrorCode::IoError)) << w.message;
  EXPECT_NE(w.message.find("cannot create the temporary file"), std::string::npos) << w.message;
  EXPECT_NE(w.message.find(dir_.string()), std::string::npos) << "the message names the path: " << w.message;
  EXPECT_EQ(readBytes(path), before);
  EXPECT_EQ(listing(), std::vector<std::string>{"scene.vbp"});
}

// --- fuzz
// ---------------------------------------------------------------------------------------------------

void fuzzPack(const Scene& scene, uint64_t seed, const PackWriteOptions& options = {});

// 2,000 random mutations of a valid pack (fixed seed): bit flips, random bytes, extreme integers written over
// header/table/record fields, truncation and extension. Half of them are resealed (checksums recomputed) so
// that they reach the structural and content checks. Every read must return (no crash, no sanitizer report
// under the sanitizer build); a success must be a valid scene.
TEST(PackFuzz, RandomMutationsNeverCrash) {
  for (const bool textured : {false, true}) {
    SCOPED_TRACE(textured ? "textured" : "plain");
    fuzzPack(textured ? makeTexturedTestScene() : makeTestScene(16, 6), textured ? 20240612 : 20240611);
  }
  SCOPED_TRACE("quantised");
  fuzzPack(makeTexturedTestScene(), 20261123, PackWriteOptions{true});
}

void fuzzPack(const Scene& scene, uint64_t seed, const PackWriteOptions& options) {
  Result<std::vector<uint8_t>> original = serializePack(scene, options);
  ASSERT_TRUE(original);
  Rng rng(seed);
  auto below = [&](uint64_t n) { return n == 0 ? 0 : rng.next() % n; };
  const uint64_t extremes[] = {0,
                               1,
                               3,
                               15,
                               16,
                               0x7FFFFFFF,
                               0xFFFFFFFF,
                               0x100000000ull,
                               uint64_t{1} << 62,
                               ~uint64_t{0},
                               ~uint64_t{0} - 15};
  size_t failures = 0, deep = 0, successes = 0;
  for (int iteration = 0; iteration < 2000; ++iteration) {
    std::vector<uint8_t> v = *original;
    const int mutations = 1 + static_cast<int>(below(4));
    for (int m = 0; m < mutations; ++m) {
      // Bias towards the header, the table and the small record sections at the front.
      const uint64_t span = below(4) == 0 ? v.size() : std::min<uint64_t>(v.size(), 1024);
      const uint64_t at = below(span);
      switch (below(5)) {
        case 0:
          v[at] ^= uint8_t(1u << below(8));
          break;
        case 1:
          v[at] = uint8_t(rng.next());
          break;
        case 2: {
          const uint64_t x = extremes[below(std::size(extremes))];
          const size_t width = below(2) ? 8 : 4;
          if (at + width <= v.size()) std::memcpy(v.data() + (at & ~uint64_t{3}), &x, width);
          break;
        }
        case 3:
          v.resize(below(v.size() + 1));
          break;
        case 4:
          v.resize(v.size() + 16 * (1 + below(4)), uint8_t(rng.next()));
          break;
      }
      if (v.empty()) break;
    }
    if (iteration % 2 == 0) reseal(v);
    Result<Scene> r = parsePack(v.data(), v.size(), "fuzz.vbp");
    if (r) {
      ++successes;
      EXPECT_TRUE(validateScene(*r));
    } else {
      ++failures;
      EXPECT_FALSE(r.error().message.empty());
      EXPECT_EQ(r.error().message.rfind("fuzz.vbp: ", 0), 0u) << r.error().message;
      if (r.error().message.find("checksum") == std::string::npos) ++deep;
    }
  }
  EXPECT_EQ(failures + successes, 2000u);
  EXPECT_GT(deep, 500u);  // the resealed half really exercises the structural and content checks
  std::printf("[          ] %zu rejected (%zu past the checksums), %zu accepted\n", failures, deep,
              successes);
}

}  // namespace
}  // namespace visbuf
