// The pack format (engine/asset/pack_{format,writer,reader}.h): round trips of a generated scene and of real assets,
// memory-mapped reads, atomic writes, and a bounded fuzz run. Hostile packs: test_pack_reader.cpp; quantised packs
// and the encoded geometry streams: test_pack_quantize.cpp.
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

TEST_F(PackFileTest, UnwritableDirectory) {
  if (geteuid() == 0)
    GTEST_SKIP() << "root ignores directory permissions (covered by FailedWriteKeepsTheOldPack)";
  const fs::path path = dir_ / "scene.vbp";
  ASSERT_TRUE(writePack(makeTestScene(16, 6), path.string()));
  const std::vector<uint8_t> before = readBytes(path);
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  Status s = writePack(makeTestScene(), path.string());
  fs::permissions(dir_, fs::perms::owner_all);
  ASSERT_FALSE(s);
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
