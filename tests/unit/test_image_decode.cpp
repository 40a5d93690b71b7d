// Image decoding for the bake (engine/asset/texture_decode.h): every PNG colour type and bit depth, interlaced
// or not, against pixels computed here from the samples written (an encoder of this file, zlib only); metadata
// chunks and segments that never change a pixel and are never parsed; corrupt files that give visbuf errors and
// print nothing; the header reader, the memory estimate and the gate that bounds the images baked at once.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "visbuf/asset/texture_bake.h"
#include "visbuf/asset/texture_decode.h"

#if VISBUF_DECODES_IMAGES
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#endif

namespace visbuf {
namespace {

using Bytes = std::vector<uint8_t>;

void put32(Bytes& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(uint8_t(v >> s));
}

Bytes zlibCompress(const Bytes& raw) {
  uLongf size = compressBound(uLong(raw.size()));
  Bytes out(size);
  EXPECT_EQ(compress2(out.data(), &size, raw.data(), uLong(raw.size()), 6), Z_OK);
  out.resize(size);
  return out;
}

void chunk(Bytes& out, const char* type, const Bytes& data) {
  put32(out, uint32_t(data.size()));
  const size_t typeAt = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put32(out, uint32_t(crc32(0, out.data() + typeAt, uInt(data.size() + 4))));
}

Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }
Bytes cat(Bytes a, const Bytes& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

struct Chunk {
  std::string type;
  Bytes data;
};

// A PNG written here. samples: channels(colourType) values per pixel, each below 2^depth, row-major.
struct PngSpec {
  uint32_t width = 1, height = 1;
  uint8_t depth = 8, colourType = 6;
  bool interlaced = false;
  Bytes plte, trns;
  std::vector<Chunk> beforeIdat, afterIdat;
};

int channelsOf(uint8_t colourType) {
  switch (colourType) {
    case 0: return 1;
    case 2: return 3;
    case 3: return 1;
    case 4: return 2;
    default: return 4;
  }
}

Bytes encodePng(const PngSpec& spec, const std::vector<uint16_t>& samples) {
  const int ch = channelsOf(spec.colourType);
  // Adam7 (PNG specification 8.2): start and step of each pass; one pass of the whole image when not interlaced.
  static const uint32_t kX0[7] = {0, 4, 0, 2, 0, 1, 0}, kY0[7] = {0, 0, 4, 0, 2, 0, 1};
  static const uint32_t kDx[7] = {8, 8, 4, 4, 2, 2, 1}, kDy[7] = {8, 8, 8, 4, 4, 2, 2};
  Bytes raw;
  for (int pass = 0; pass < (spec.interlaced ? 7 : 1); ++pass) {
    const uint32_t x0 = spec.interlaced ? kX0[pass] : 0, y0 = spec.interlaced ? kY0[pass] : 0;
    const uint32_t dx = spec.interlaced ? kDx[pass] : 1, dy = spec.interlaced ? kDy[pass] : 1;
    if (x0 >= spec.width || y0 >= spec.height) continue;  // an empty pass has no rows at all
    for (uint32_t y = y0; y < spec.height; y += dy) {
      raw.push_back(0);  // filter: none
      uint32_t bits = 0, nbits = 0;
      for (uint32_t x = x0; x < spec.width; x += dx) {
        for (int c = 0; c < ch; ++c) {
          const uint16_t v = samples[(size_t(y) * spec.width + x) * size_t(ch) + size_t(c)];
          if (spec.depth == 16) {
            raw.push_back(uint8_t(v >> 8));
            raw.push_back(uint8_t(v));
          } else {
            bits = bits << spec.depth | v;
            nbits += spec.depth;
            if (nbits == 8) {
              raw.push_back(uint8_t(bits));
              bits = nbits = 0;
            }
          }
        }
      }
      if (nbits) raw.push_back(uint8_t(bits << (8 - nbits)));
    }
  }
  Bytes out = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  Bytes ihdr;
  put32(ihdr, spec.width);
  put32(ihdr, spec.height);
  ihdr.insert(ihdr.end(), {spec.depth, spec.colourType, 0, 0, uint8_t(spec.interlaced ? 1 : 0)});
  chunk(out, "IHDR", ihdr);
  for (const Chunk& c : spec.beforeIdat) chunk(out, c.type.c_str(), c.data);
  if (!spec.plte.empty()) chunk(out, "PLTE", spec.plte);
  if (!spec.trns.empty()) chunk(out, "tRNS", spec.trns);
  const Bytes z = zlibCompress(raw);
  const size_t half = z.size() / 2;  // two IDATs: the stream spans chunks
  chunk(out, "IDAT", Bytes(z.begin(), z.begin() + std::ptrdiff_t(half)));
  chunk(out, "IDAT", Bytes(z.begin() + std::ptrdiff_t(half), z.end()));
  for (const Chunk& c : spec.afterIdat) chunk(out, c.type.c_str(), c.data);
  chunk(out, "IEND", {});
  return out;
}

std::vector<uint16_t> randomSamples(const PngSpec& spec, uint32_t seed) {
  std::mt19937 rng(seed);
  const uint32_t levels = spec.colourType == 3 ? uint32_t(spec.plte.size() / 3) : 1u << spec.depth;
  std::vector<uint16_t> s(size_t(spec.width) * spec.height * size_t(channelsOf(spec.colourType)));
  for (uint16_t& v : s) v = uint16_t(rng() % levels);
  return s;
}

// The RGBA the PNG specification gives each pixel, in the file's own range (8-bit: 0..255, 16-bit: 0..65535):
// grey below 8 bits scaled to 8 (v * 255 / (2^depth - 1)), palette looked up, tRNS as alpha, grey to RGB.
std::vector<uint32_t> expectedRgba(const PngSpec& spec, const std::vector<uint16_t>& samples) {
  const int ch = channelsOf(spec.colourType);
  const uint32_t max = spec.depth == 16 ? 65535 : 255;
  const uint32_t fileMax = (1u << spec.depth) - 1;
  std::vector<uint32_t> out;
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p) {
    const uint16_t* s = &samples[p * size_t(ch)];
    uint32_t r, g, b, a = max;
    auto scale = [&](uint32_t v) { return spec.depth < 8 ? v * 255 / fileMax : v; };
    auto trns16 = [&](size_t i) { return uint32_t(spec.trns[2 * i]) << 8 | spec.trns[2 * i + 1]; };
    switch (spec.colourType) {
      case 3:
        r = spec.plte[3 * s[0]], g = spec.plte[3 * s[0] + 1], b = spec.plte[3 * s[0] + 2];
        if (s[0] < spec.trns.size()) a = spec.trns[s[0]];
        break;
      case 0:
      case 4:
        r = g = b = scale(s[0]);
        if (spec.colourType == 4) a = s[1];
        if (spec.colourType == 0 && !spec.trns.empty() && s[0] == trns16(0)) a = 0;
        break;
      default:
        r = s[0], g = s[1], b = s[2];
        if (spec.colourType == 6) a = s[3];
        if (spec.colourType == 2 && !spec.trns.empty() && r == trns16(0) && g == trns16(1) && b == trns16(2)) a = 0;
    }
    out.insert(out.end(), {r, g, b, a});
  }
  return out;
}

#if VISBUF_DECODES_IMAGES

// Decodes (linear colour space: 16-bit values are code / 65535) and compares with expectedRgba. withTrns: a tRNS
// chunk too (palette: the first entries partly transparent; grey, RGB: the first pixel's colour transparent).
void expectDecodes(PngSpec spec, uint32_t seed, bool withTrns) {
  const std::vector<uint16_t> samples = randomSamples(spec, seed);
  if (withTrns) {
    if (spec.colourType == 3) spec.trns = Bytes{0, 128, 255}, spec.trns.resize(std::min<size_t>(3, spec.plte.size() / 3));
    for (int c = 0; c < (spec.colourType == 2 ? 3 : spec.colourType == 0 ? 1 : 0); ++c)
      spec.trns.insert(spec.trns.end(), {uint8_t(samples[size_t(c)] >> 8), uint8_t(samples[size_t(c)])});
  }
  const Bytes png = encodePng(spec, samples);
  const std::string what = "depth " + std::to_string(spec.depth) + " colour type " +
                           std::to_string(spec.colourType) + (spec.interlaced ? " Adam7" : "") +
                           (spec.trns.empty() ? "" : " tRNS") + " " + std::to_string(spec.width) + "x" +
                           std::to_string(spec.height);
  Result<DecodedImage> d = decodeImageForBake(png.data(), png.size(), "t.png", ColorSpace::Linear);
  ASSERT_TRUE(d) << what << ": " << d.error().message;
  ASSERT_EQ(d->width, spec.width);
  ASSERT_EQ(d->height, spec.height);
  const std::vector<uint32_t> want = expectedRgba(spec, samples);
  if (!spec.trns.empty() && spec.colourType != 3) {
    ASSERT_EQ(want[3], 0u) << what;  // the tRNS colour is used
  }
  if (spec.depth == 16) {
    ASSERT_TRUE(d->codes.empty()) << what;
    ASSERT_EQ(d->linear.rgba.size(), want.size()) << what;
    for (size_t i = 0; i < want.size(); ++i)
      ASSERT_NEAR(d->linear.rgba[i], double(want[i]) / 65535.0, 2e-7) << what << ", value " << i;
  } else {
    ASSERT_EQ(d->codes.size(), want.size()) << what;
    for (size_t i = 0; i < want.size(); ++i) ASSERT_EQ(d->codes[i], want[i]) << what << ", value " << i;
  }
}

Bytes palette(size_t entries) {
  Bytes p;
  for (size_t i = 0; i < entries; ++i) p.insert(p.end(), {uint8_t(i * 37 + 5), uint8_t(i * 91 + 7), uint8_t(255 - i)});
  return p;
}

TEST(ImageDecode, EveryPngColourTypeAndDepthInterlacedOrNot) {
  struct Kind {
    uint8_t colourType;
    std::vector<uint8_t> depths;
  };
  const Kind kinds[] = {{0, {1, 2, 4, 8, 16}}, {2, {8, 16}}, {3, {1, 2, 4, 8}}, {4, {8, 16}}, {6, {8, 16}}};
  uint32_t seed = 1;
  for (const Kind& k : kinds) {
    for (uint8_t depth : k.depths) {
      for (bool interlaced : {false, true}) {
        // 13 x 11: every Adam7 pass partly filled; 1 x 1 and 3 x 2: the empty passes libpng skips.
        for (auto [w, h] : {std::pair{13u, 11u}, std::pair{1u, 1u}, std::pair{3u, 2u}}) {
          PngSpec spec;
          spec.width = w, spec.height = h, spec.depth = depth, spec.colourType = k.colourType;
          spec.interlaced = interlaced;
          if (k.colourType == 3) spec.plte = palette(std::min<size_t>(size_t(1) << depth, 200));
          expectDecodes(spec, seed++, false);
          if (k.colourType != 4 && k.colourType != 6) expectDecodes(spec, seed++, true);
        }
      }
    }
  }
}

TEST(ImageDecode, SixteenBitSrgbIsLinearisedFromCodeOver65535) {
  PngSpec spec;
  spec.width = 64, spec.height = 4, spec.depth = 16, spec.colourType = 6;
  const std::vector<uint16_t> samples = randomSamples(spec, 9);
  const Bytes png = encodePng(spec, samples);
  Result<DecodedImage> d = decodeImageForBake(png.data(), png.size(), "t.png", ColorSpace::Srgb);
  ASSERT_TRUE(d) << d.error().message;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double c = samples[i] / 65535.0;
    const double want = i % 4 == 3 ? c : c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    ASSERT_NEAR(d->linear.rgba[i], want, 2e-6) << i;
  }
}

// An XMP packet nested `depth` elements deep (OpenImageIO's recursive XML parser overflowed the stack on 20,000).
std::string nestedXmp(int depth) {
  std::string s = "<x:xmpmeta xmlns:x='adobe:ns:meta/'>";
  for (int i = 0; i < depth; ++i) s += "<a>";
  for (int i = 0; i < depth; ++i) s += "</a>";
  return s + "</x:xmpmeta>";
}

std::vector<Chunk> metadataChunks() {
  const std::string xmp = nestedXmp(20000);
  const Bytes key = text(std::string("XML:com.adobe.xmp") + '\0');
  Bytes exif = text("MM");
  exif.insert(exif.end(), {0, 42, 0, 0, 0, 8, 0xFF, 0xFF});  // TIFF header, then an IFD claiming 65535 entries
  return {
      {"iTXt", cat(cat(key, Bytes{0, 0, 0, 0}), text(xmp))},
      {"iTXt", cat(cat(key, Bytes{1, 0, 0, 0}), zlibCompress(text(xmp)))},
      {"zTXt", cat(cat(key, Bytes{0}), zlibCompress(text(xmp)))},
      {"tEXt", cat(key, text(xmp))},
      {"tEXt", cat(text(std::string("Raw profile type exif") + '\0'), text("\nexif\n 99999\n45786966"))},
      {"eXIf", exif},
      {"iCCP", cat(text(std::string("icc") + '\0' + '\0'), zlibCompress(Bytes(5000, 0xAB)))},
      {"gAMA", {0, 0, 0, 1}},
      {"sRGB", {9}},
      {"cHRM", Bytes(32, 0xFF)},
      {"pHYs", Bytes(9, 0xFF)},
      {"tIME", Bytes(7, 0xFF)},
      {"sPLT", cat(text(std::string("p") + '\0'), Bytes{8, 1, 2, 3})},
      {"vsBf", Bytes(100, 1)},  // private, ancillary
  };
}

TEST(ImageDecode, PngMetadataChunksAreSkippedUnreadAndLeaveThePixels) {
  for (const auto& [type, interlaced, depth] : {std::tuple{6, false, 8}, std::tuple{3, true, 8},
                                                std::tuple{4, false, 16}, std::tuple{2, true, 16}}) {
    PngSpec plain;
    plain.width = 23, plain.height = 17, plain.depth = uint8_t(depth), plain.colourType = uint8_t(type);
    plain.interlaced = interlaced;
    if (type == 3) plain.plte = palette(256);
    const std::vector<uint16_t> samples = randomSamples(plain, 77);
    PngSpec withMetadata = plain;
    withMetadata.beforeIdat = metadataChunks();
    withMetadata.afterIdat = metadataChunks();
    const Bytes a = encodePng(plain, samples), b = encodePng(withMetadata, samples);
    ASSERT_GT(b.size(), a.size() + 100000);
    Result<DecodedImage> da = decodeImageForBake(a.data(), a.size(), "plain.png", ColorSpace::Srgb);
    Result<DecodedImage> db = decodeImageForBake(b.data(), b.size(), "meta.png", ColorSpace::Srgb);
    ASSERT_TRUE(da) << da.error().message;
    ASSERT_TRUE(db) << db.error().message;
    EXPECT_EQ(da->codes, db->codes);
    EXPECT_EQ(da->linear.rgba, db->linear.rgba);  // bit for bit
    if (depth == 8) {
      const std::vector<uint32_t> want = expectedRgba(plain, samples);
      ASSERT_EQ(db->codes.size(), want.size());
      for (size_t i = 0; i < want.size(); ++i) ASSERT_EQ(db->codes[i], want[i]) << i;
    }
  }
}

// A damaged chunk CRC on a skipped chunk does not matter (it is not read); on IDAT it is an error.
TEST(ImageDecode, CorruptPngsAreVisbufErrorsAndPrintNothing) {
  PngSpec spec;
  spec.width = 40, spec.height = 30;
  const Bytes good = encodePng(spec, randomSamples(spec, 5));
  std::vector<std::pair<std::string, Bytes>> bad;
  Bytes crc = good;
  crc[good.size() - 12 - 5] ^= 1;  // the last IDAT's CRC (IEND is the last 12 bytes)
  bad.emplace_back("IDAT CRC", crc);
  bad.emplace_back("truncated", Bytes(good.begin(), good.begin() + std::ptrdiff_t(good.size() / 2)));
  Bytes zlib = good;
  for (size_t i = 45; i < 60; ++i) zlib[i] ^= 0x5A;
  bad.emplace_back("zlib data", zlib);
  Bytes ihdr = good;
  ihdr[24] = 3;  // bit depth 3
  bad.emplace_back("bit depth", ihdr);
  bad.emplace_back("signature and half an IHDR", Bytes(good.begin(), good.begin() + 20));
  Bytes noIend(good.begin(), good.end() - 12);
  bad.emplace_back("no IEND", noIend);
  for (const auto& [what, bytes] : bad) {
    testing::internal::CaptureStderr();
    testing::internal::CaptureStdout();
    Result<DecodedImage> d = decodeImageForBake(bytes.data(), bytes.size(), "scene: image 2 'bad.png'", ColorSpace::Srgb);
    const std::string err = testing::internal::GetCapturedStderr(), out = testing::internal::GetCapturedStdout();
    ASSERT_FALSE(d) << what;
    EXPECT_EQ(d.error().code, ErrorCode::MalformedInput) << what << ": " << d.error().message;
    EXPECT_EQ(d.error().message.rfind("scene: image 2 'bad.png': ", 0), 0u) << d.error().message;
    EXPECT_EQ(err, "") << what;
    EXPECT_EQ(out, "") << what;
  }
}

// A JPEG written by OpenImageIO (libjpeg), then given metadata segments after SOI.
Bytes writeJpeg(uint32_t width, uint32_t height, bool progressive) {
  std::vector<uint8_t> rgb(size_t(width) * height * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t((i * 7) ^ (i >> 5));
  std::vector<unsigned char> file;
  OIIO::Filesystem::IOVecOutput proxy(file);
  auto out = OIIO::ImageOutput::create("jpeg");
  EXPECT_TRUE(out);
  OIIO::ImageSpec spec(int(width), int(height), 3, OIIO::TypeDesc::UINT8);
  spec.attribute("jpeg:progressive", progressive ? 1 : 0);
  EXPECT_TRUE(out->set_ioproxy(&proxy));
  EXPECT_TRUE(out->open("t.jpg", spec)) << out->geterror();
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data())) << out->geterror();
  out->close();
  return Bytes(file.begin(), file.end());
}

Bytes withSegments(const Bytes& jpeg, const std::vector<std::pair<uint8_t, Bytes>>& segments) {
  Bytes out(jpeg.begin(), jpeg.begin() + 2);  // SOI
  for (const auto& [marker, payload] : segments) {
    out.insert(out.end(), {0xFF, marker, uint8_t((payload.size() + 2) >> 8), uint8_t(payload.size() + 2)});
    out.insert(out.end(), payload.begin(), payload.end());
  }
  out.insert(out.end(), jpeg.begin() + 2, jpeg.end());
  return out;
}

TEST(ImageDecode, JpegMetadataSegmentsAreNeverParsedAndLeaveThePixels) {
  const std::string xmp = "http://ns.adobe.com/xap/1.0/" + std::string(1, '\0') + nestedXmp(8000).substr(0, 65000);
  Bytes iptc = text(std::string("Photoshop 3.0") + '\0' + "8BIM");
  iptc.insert(iptc.end(), {0x04, 0x04, 0, 0, 0x7F, 0xFF, 0xFF, 0xFF});  // a resource longer than the segment
  const std::vector<std::pair<uint8_t, Bytes>> segments = {
      {0xE1, text(xmp)}, {0xE1, cat(text(std::string("Exif") + '\0' + '\0'), Bytes{'M', 'M', 0, 42, 0, 0, 0, 8, 0xFF})},
      {0xE2, cat(text(std::string("ICC_PROFILE") + '\0'), Bytes{1, 1, 0xFF, 0xFF})}, {0xED, iptc},
      {0xFE, Bytes(60000, 'c')}};
  for (bool progressive : {false, true}) {
    const Bytes plain = writeJpeg(45, 31, progressive);
    const Bytes meta = withSegments(plain, segments);
    Result<DecodedImage> a = decodeImageForBake(plain.data(), plain.size(), "a.jpg", ColorSpace::Srgb);
    Result<DecodedImage> b = decodeImageForBake(meta.data(), meta.size(), "b.jpg", ColorSpace::Srgb);
    ASSERT_TRUE(a) << a.error().message;
    ASSERT_TRUE(b) << b.error().message;
    EXPECT_EQ(a->codes, b->codes);
    ASSERT_EQ(a->codes.size(), size_t(45) * 31 * 4);
    for (size_t i = 3; i < a->codes.size(); i += 4) ASSERT_EQ(a->codes[i], 255);
  }
}

TEST(ImageDecode, HeadersAreReadFromTheBytesAlone) {
  PngSpec spec;
  spec.width = 300, spec.height = 7, spec.depth = 16, spec.colourType = 0, spec.interlaced = true;
  const Bytes png = encodePng(spec, randomSamples(spec, 1));
  Result<ImageHeader> h = readImageHeader(png.data(), png.size(), "p");
  ASSERT_TRUE(h) << h.error().message;
  EXPECT_EQ(h->format, ImageFormat::Png);
  EXPECT_EQ(h->width, 300u);
  EXPECT_EQ(h->height, 7u);
  EXPECT_EQ(h->bitDepth, 16u);
  EXPECT_TRUE(h->interlaced);
  const Bytes jpeg = withSegments(writeJpeg(33, 17, true), {{0xE1, Bytes(1000, 0xFF)}});
  h = readImageHeader(jpeg.data(), jpeg.size(), "j");
  ASSERT_TRUE(h) << h.error().message;
  EXPECT_EQ(h->format, ImageFormat::Jpeg);
  EXPECT_EQ(h->width, 33u);
  EXPECT_EQ(h->height, 17u);
  EXPECT_EQ(h->components, 3u);
  EXPECT_TRUE(h->progressive);
  const Bytes gif = text("GIF89a");
  EXPECT_FALSE(readImageHeader(gif.data(), gif.size(), "g"));
  EXPECT_FALSE(readImageHeader(png.data(), 20, "cut"));
}

#else  // built without OpenImageIO: decoding is refused as such

TEST(ImageDecode, RefusedWithoutOpenImageIO) {
  PngSpec spec;
  const Bytes png = encodePng(spec, {1, 2, 3, 4});
  Result<DecodedImage> d = decodeImageForBake(png.data(), png.size(), "t.png", ColorSpace::Linear);
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().code, ErrorCode::Unsupported);
}

#endif

// The estimate (texture_decode.h) for the budget's largest images, written out by hand.
TEST(ImageDecode, PeakEstimatePerFormat) {
  const uint64_t px = uint64_t{8192} * 8192, s2 = uint64_t{2048} * 2048;
  ImageHeader png8{ImageFormat::Png, 8192, 8192, 8, 0, false, false};
  ImageHeader png16{ImageFormat::Png, 8192, 8192, 16, 0, false, true};
  ImageHeader jpeg{ImageFormat::Jpeg, 8192, 8192, 8, 3, false, false};
  ImageHeader progressive{ImageFormat::Jpeg, 8192, 8192, 8, 3, true, false};
  EXPECT_EQ(imageBakePeakBytes(png8, 2048), 20 * px + 24 * s2);
  EXPECT_EQ(imageBakePeakBytes(png16, 2048), 20 * px + 24 * s2);
  EXPECT_EQ(imageBakePeakBytes(jpeg, 2048), 20 * px + 24 * s2);
  EXPECT_EQ(imageBakePeakBytes(progressive, 2048), 20 * px + 24 * s2);  // 4 + 6 B/pixel + 64 MiB < 20 B/pixel
  ImageHeader thin{ImageFormat::Jpeg, 16, 16, 8, 3, true, false};
  EXPECT_EQ(imageBakePeakBytes(thin, 2048), 16 * 16 * 4 + (uint64_t{64} << 20) + 16 * 16 * 6 + 16 * 16 * 24);
  // At the default pixel budget every format stays within the in-flight budget: one such image at a time.
  EXPECT_LE(imageBakePeakBytes(png16, 2048), kImageBakeMemoryBudget);
}

TEST(ImageDecode, GateKeepsTheReservedBytesWithinTheBudgetAndAdmitsALoneLargeOne) {
  ImageMemoryGate gate(100);
  gate.acquire(1000);  // alone: admitted, however large
  gate.release(1000);
  std::atomic<int> held{0}, most{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 50; ++i) {
        gate.acquire(40);  // at most two at a time
        const int now = ++held;
        for (int seen = most.load(); now > seen && !most.compare_exchange_weak(seen, now);) {
        }
        std::this_thread::yield();
        --held;
        gate.release(40);
      }
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_LE(most.load(), 2);
  EXPECT_GE(most.load(), 1);
}

}  // namespace
}  // namespace visbuf
