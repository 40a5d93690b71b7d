// zstd section encoding (pack_section_codec.h, docs/pack-format.md "Section encodings"): compressed packs load to
// exactly the scene of their raw twin, byte ranges decode right across frame and class boundaries, and hostile
// stored bytes (lying sizes, truncated or extra frames, skippable and dictionary frames, missing checksums,
// decompression bombs) are refused with a message naming the section and frame.
#include <zstd.h>

#include "pack_test_util.h"
#include "visbuf/asset/pack_section_codec.h"

namespace visbuf {
namespace {

using namespace pack_test;

// Bytes that compress (runs and a repeating ramp) with a noisy stretch that does not.
std::vector<uint8_t> mixedBytes(size_t n, uint32_t seed) {
  std::vector<uint8_t> v(n);
  std::mt19937 rng(seed);
  for (size_t i = 0; i < n; ++i) v[i] = (i / 4096) % 3 == 2 ? uint8_t(rng()) : uint8_t((i / 64) * 7 + seed);
  return v;
}

// makeTexturedTestScene plus an RGBA8 class of 512^2 (1.4 MB: frames of 1 MiB straddle its ends and the other
// classes') so that "texels" is several frames.
Scene makeLargeTexturedScene() {
  Scene scene = makeTexturedTestScene();
  TextureClass c;
  c.size = 512;
  c.colorSpace = ColorSpace::Linear;
  c.layers = 1;
  c.mipCount = TextureClass::mipCountFor(c.size);
  c.texels = mixedBytes(c.totalBytes(), 3);
  scene.textureClasses.insert(scene.textureClasses.begin() + 1, std::move(c));
  for (Texture& t : scene.textures)
    if (t.sizeClass >= 1) ++t.sizeClass;
  scene.textures.push_back({"big", -1, ColorSpace::Linear, 1, 0, 512, 512});
  return scene;
}

Result<std::vector<uint8_t>> serializeAt(const Scene& scene, int level, PackWriteReport* report = nullptr) {
  PackWriteOptions o;
  o.compressionLevel = level;
  return serializePack(scene, o, report);
}

const PackSectionInfo* info(const PackWriteReport& r, const std::string& name) {
  for (const PackSectionInfo& s : r.sections)
    if (s.name == name) return &s;
  return nullptr;
}

TEST(PackZstd, CompressedPackLoadsToTheSameSceneAsItsRawTwin) {
  const Scene scene = makeLargeTexturedScene();
  PackWriteReport rawReport, zReport;
  Result<std::vector<uint8_t>> raw = serializeAt(scene, 0, &rawReport);
  Result<std::vector<uint8_t>> z = serializeAt(scene, pack::kDefaultZstdLevel, &zReport);
  ASSERT_TRUE(raw && z);
  for (const PackSectionInfo& s : rawReport.sections) EXPECT_EQ(s.encoding, pack::kSectionRaw) << s.name;
  const PackSectionInfo* texels = info(zReport, "texels");
  ASSERT_NE(texels, nullptr);
  EXPECT_EQ(texels->encoding, pack::kSectionZstd);
  EXPECT_GT(texels->size, pack::kZstdChunkBytes);  // more than one frame
  EXPECT_LT(texels->storedSize, texels->size * 3 / 4);
  EXPECT_LT(z->size(), raw->size());
  // Small sections stay raw.
  EXPECT_EQ(info(zReport, "scene")->encoding, pack::kSectionRaw);
  Result<Scene> a = parse(*raw);
  Result<Scene> b = parse(*z);
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  expectScenesEqual(*a, *b);
  expectScenesEqual(scene, *b);
  // Deterministic: the same scene gives the same bytes.
  Result<std::vector<uint8_t>> again = serializeAt(scene, pack::kDefaultZstdLevel);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *z);
  // The read's scratch: at most the two frames that straddle each class's ends.
  PackReadStats stats;
  ASSERT_TRUE(parsePack(z->data(), z->size(), "pack.vbp", &stats));
  EXPECT_GT(stats.peakScratchBytes, 0u);
  EXPECT_LE(stats.peakScratchBytes, 2 * pack::kZstdChunkBytes * scene.textureClasses.size());
}

TEST(PackZstd, RangesDecodeAcrossFrameBoundaries) {
  const std::vector<uint8_t> data = mixedBytes(5 * 4096 + 123, 7);
  Result<std::vector<uint8_t>> stored = pack::encodeZstdSection(data.data(), data.size(), 3, 4096);
  ASSERT_TRUE(stored);
  Result<pack::ZstdSection> z = pack::ZstdSection::open(stored->data(), stored->size(), data.size());
  ASSERT_TRUE(z) << z.error().message;
  EXPECT_EQ(z->frameCount(), 6u);
  const std::pair<uint64_t, uint64_t> ranges[] = {{0, data.size()}, {0, 1},         {4095, 4097}, {4096, 8192},
                                                  {100, 20000},     {20480, 20603}, {7, 7}};
  for (auto [begin, end] : ranges) {
    std::vector<uint8_t> out(end - begin, 0xEE);
    ASSERT_TRUE(z->decode(begin, end, out.data())) << begin << ".." << end;
    EXPECT_TRUE(std::equal(out.begin(), out.end(), data.begin() + int64_t(begin))) << begin << ".." << end;
  }
  std::vector<uint8_t> out(8);
  EXPECT_FALSE(z->decode(data.size() - 4, data.size() + 4, out.data()));  // past the end: refused, not read
  // Bytes do not depend on the thread count: frames are fixed slices compressed on their own.
  Result<std::vector<uint8_t>> again = pack::encodeZstdSection(data.data(), data.size(), 3, 4096);
  ASSERT_TRUE(again);
  EXPECT_EQ(*again, *stored);
}

// --- hostile stored bytes

// One zstd frame of `data` with the given frame parameters.
std::vector<uint8_t> frameOf(const std::vector<uint8_t>& data, bool checksum = true, bool contentSize = true) {
  ZSTD_CCtx* c = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, checksum ? 1 : 0);
  ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, contentSize ? 1 : 0);
  std::vector<uint8_t> out(ZSTD_compressBound(data.size()));
  size_t n;
  if (contentSize) {
    n = ZSTD_compress2(c, out.data(), out.size(), data.data(), data.size());
  } else {  // streamed without a pledged size: the header has no content size
    ZSTD_outBuffer o{out.data(), out.size(), 0};
    ZSTD_inBuffer in{data.data(), data.size(), 0};
    n = ZSTD_compressStream2(c, &o, &in, ZSTD_e_end);
    EXPECT_EQ(n, 0u);
    n = o.pos;
  }
  ZSTD_freeCCtx(c);
  EXPECT_FALSE(ZSTD_isError(n));
  out.resize(n);
  return out;
}

// The stored bytes of a zstd section: header + frame table + frames.
std::vector<uint8_t> storedOf(uint32_t chunk, const std::vector<std::vector<uint8_t>>& frames,
                              uint32_t frameCount = ~0u, uint64_t reserved = 0) {
  const pack::ZstdSectionHeader h{chunk, frameCount == ~0u ? uint32_t(frames.size()) : frameCount, reserved};
  std::vector<uint8_t> out(sizeof(h));
  std::memcpy(out.data(), &h, sizeof(h));
  for (const auto& f : frames) {
    const uint32_t n = uint32_t(f.size());
    out.insert(out.end(), reinterpret_cast<const uint8_t*>(&n), reinterpret_cast<const uint8_t*>(&n) + 4);
  }
  for (const auto& f : frames) out.insert(out.end(), f.begin(), f.end());
  return out;
}

// A raw pack whose "texels" section is replaced by `stored` as a zstd section declaring `decodedSize` bytes.
std::vector<uint8_t> packWithTexels(const std::vector<uint8_t>& stored, uint64_t decodedSize) {
  Result<std::vector<uint8_t>> raw = serializeAt(makeTexturedTestScene(), 0);
  EXPECT_TRUE(raw);
  std::vector<RawSection> sections = splitPack(*raw);
  RawSection& t = rawSection(sections, "texels");
  t.entry.encoding = pack::kSectionZstd;
  t.entry.size = t.entry.count = decodedSize;
  t.bytes = stored;
  return joinPack(*raw, sections);
}

TEST(PackZstd, HostileFramesAreRefusedByName) {
  Result<std::vector<uint8_t>> raw = serializeAt(makeTexturedTestScene(), 0);
  ASSERT_TRUE(raw);
  const std::vector<uint8_t> texels = sectionBytes(*raw, "texels");
  const uint32_t chunk = pack::kMinZstdChunkBytes;
  ASSERT_LT(texels.size(), chunk);  // one frame
  const std::vector<uint8_t> good = frameOf(texels);
  // The honest section loads, to the raw pack's scene.
  {
    Result<Scene> r = parse(packWithTexels(storedOf(chunk, {good}), texels.size()));
    ASSERT_TRUE(r) << r.error().message;
    Result<Scene> expected = parse(*raw);
    ASSERT_TRUE(expected);
    expectScenesEqual(*expected, *r);
  }
  auto refuses = [&](const std::vector<uint8_t>& stored, uint64_t decodedSize, const std::string& text) {
    const Result<Scene> r = parse(packWithTexels(stored, decodedSize));
    const ::testing::AssertionResult named = failsWith(r, "section 'texels': zstd");
    return named ? failsWith(r, text) : named;
  };
  // Lying sizes: the section declares more or fewer bytes than the frame holds.
  EXPECT_TRUE(refuses(storedOf(chunk, {good}), texels.size() + 16, "declares " + std::to_string(texels.size())));
  EXPECT_TRUE(refuses(storedOf(chunk, {good}), texels.size() - 16, "declares " + std::to_string(texels.size())));
  // A frame that decodes to more than the section declares needs more frames than the table has.
  EXPECT_TRUE(refuses(storedOf(chunk, {good}), chunk + 16, "field 'frameCount' 1 differs"));
  // Truncated frame, trailing bytes, a second frame inside the first's range.
  EXPECT_TRUE(refuses(storedOf(chunk, {{good.begin(), good.end() - 1}}), texels.size(), "truncated or damaged"));
  std::vector<uint8_t> trailing = good;
  trailing.insert(trailing.end(), {1, 2, 3});
  EXPECT_TRUE(refuses(storedOf(chunk, {trailing}), texels.size(), "trailing bytes"));
  std::vector<uint8_t> twice = good;
  twice.insert(twice.end(), good.begin(), good.end());
  EXPECT_TRUE(refuses(storedOf(chunk, {twice}), texels.size(), "trailing bytes"));
  // Frames a pack never holds: skippable, with a dictionary ID, without checksum, without content size.
  std::vector<uint8_t> skippable = {0x50, 0x2A, 0x4D, 0x18, 4, 0, 0, 0, 1, 2, 3, 4};
  EXPECT_TRUE(refuses(storedOf(chunk, {skippable}), texels.size(), "skippable frame"));
  std::vector<uint8_t> dictionary = good;
  dictionary[4] |= 0x01;
  EXPECT_TRUE(refuses(storedOf(chunk, {dictionary}), texels.size(), "dictionary"));
  EXPECT_TRUE(refuses(storedOf(chunk, {frameOf(texels, false)}), texels.size(), "no content checksum"));
  EXPECT_TRUE(refuses(storedOf(chunk, {frameOf(texels, true, false)}), texels.size(), "declares no content size"));
  EXPECT_TRUE(refuses(storedOf(chunk, {{0x28, 0xB5, 0x2F, 0xFC, 0, 0}}), texels.size(), "not a zstd frame"));
  // Damaged content (the section CRC resealed over it): the frame's content checksum or block decode refuses it.
  std::vector<uint8_t> damaged = good;
  damaged[damaged.size() - 1] ^= 0x5A;  // the content checksum itself
  EXPECT_TRUE(failsWith(parse(packWithTexels(storedOf(chunk, {damaged}), texels.size())),
                        "section 'texels' (class 0): zstd frame 0: "));
  // The header and table.
  EXPECT_TRUE(refuses(storedOf(3000, {good}), texels.size(), "'chunkBytes' 3000 is not a power of two"));
  EXPECT_TRUE(refuses(storedOf(chunk << 13, {good}), texels.size(), "is not a power of two in"));
  EXPECT_TRUE(refuses(storedOf(chunk, {good}, 1, 9), texels.size(), "field 'reserved' is 9"));
  EXPECT_TRUE(refuses(storedOf(chunk, {good}, 200), texels.size(), "field 'frameCount' 200 differs"));
  std::vector<uint8_t> shortTable = storedOf(chunk, {good});
  shortTable.resize(18);
  EXPECT_TRUE(refuses(shortTable, texels.size(), "table of 1 frame sizes runs past"));
  std::vector<uint8_t> extra = storedOf(chunk, {good});
  extra.push_back(0);
  EXPECT_TRUE(refuses(extra, texels.size(), "but the section stores"));
  std::vector<uint8_t> lyingTable = storedOf(chunk, {good});
  const uint32_t huge = 0xFFFFFFF0u;
  std::memcpy(lyingTable.data() + 16, &huge, 4);
  EXPECT_TRUE(refuses(lyingTable, texels.size(), "runs past the"));
  EXPECT_TRUE(refuses({1, 2, 3}, texels.size(), "smaller than the 16-byte header"));
}

TEST(PackZstd, BadEntriesAndBombsAreRefusedBeforeDecoding) {
  Result<std::vector<uint8_t>> z = serializeAt(makeLargeTexturedScene(), pack::kDefaultZstdLevel);
  ASSERT_TRUE(z);
  const size_t idx = sectionIndex(*z, "texels");
  const pack::SectionEntry texels = entryOf(*z, idx);
  ASSERT_EQ(texels.encoding, pack::kSectionZstd);
  auto edited = [&](auto edit) {
    std::vector<uint8_t> v = *z;
    pack::SectionEntry e = texels;
    edit(e);
    std::memcpy(v.data() + sizeof(pack::Header) + idx * sizeof(pack::SectionEntry), &e, sizeof(e));
    reseal(v);
    return parse(v);
  };
  // A bomb: a section that declares 1 TiB decoded (count and size consistent) stops at the budget, before the
  // frame table is read or anything is allocated.
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.size = e.count = uint64_t{1} << 40; }),
                        "more than the reader's budget", ErrorCode::CapacityExceeded));
  // Within the budget, the frame table must still account for every declared byte.
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.size = e.count = uint64_t{1} << 30; }),
                        "section 'texels': zstd: field 'frameCount'"));
  // A smaller budget refuses the honest pack, naming the option that raises it.
  PackReadOptions tight;
  tight.maxDecodedBytes = texels.size - 1;
  EXPECT_TRUE(failsWith(parsePack(z->data(), z->size(), "pack.vbp", tight), "--max-import-memory",
                        ErrorCode::CapacityExceeded));
  tight.maxDecodedBytes = texels.size + (uint64_t{1} << 20);  // + the geometry sections
  EXPECT_TRUE(parsePack(z->data(), z->size(), "pack.vbp", tight));
  // Entry fields.
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.encoding = 2; }), "field 'encoding' 2 is unknown"));
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.reserved = 1; }), "field 'reserved' is 1"));
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.encoding = pack::kSectionRaw; }),
                        "field 'storedSize'"));
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.size = e.count = 0; }), "empty sections are raw"));
  EXPECT_TRUE(failsWith(edited([](pack::SectionEntry& e) { e.storedSize = uint64_t{1} << 62; }),
                        "section 'texels' runs past the end of the file"));
  // The checksum covers the stored (compressed) bytes: a flipped byte stops before any decoder runs.
  std::vector<uint8_t> flipped = *z;
  flipped[texels.offset + texels.storedSize / 2] ^= 0x01;
  EXPECT_TRUE(failsWith(parse(flipped), "section 'texels': checksum mismatch"));
}

}  // namespace
}  // namespace visbuf
