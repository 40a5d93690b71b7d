// zstd section encoding (pack_section_codec.h). The frame checks read the frame header as RFC 8878 lays it out:
// magic (4 bytes, 0xFD2FB528 little-endian), then the Frame_Header_Descriptor byte: bits 7-6 the content size
// field's size, bit 5 single segment, bit 3 reserved (0), bit 2 content checksum, bits 1-0 the dictionary ID
// field's size. The stable zstd API (ZSTD_getFrameContentSize, ZSTD_findFrameCompressedSize) does the rest.
#include "visbuf/asset/pack_section_codec.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <string>

#include "visbuf/asset/pack_format.h"

namespace visbuf::pack {

namespace {

constexpr uint32_t kZstdMagic = 0xFD2FB528u;
constexpr uint32_t kSkippableMagicMask = 0xFFFFFFF0u;
constexpr uint32_t kSkippableMagic = 0x184D2A50u;

Error malformed(std::string message) { return makeError(ErrorCode::MalformedInput, std::move(message)); }

struct CCtxFree {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};
struct DCtxFree {
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};

}  // namespace

Result<std::vector<uint8_t>> encodeZstdSection(const uint8_t* data, size_t size, int level, uint32_t chunkBytes) {
  if (size == 0 || !std::has_single_bit(chunkBytes) || chunkBytes < kMinZstdChunkBytes ||
      chunkBytes > kMaxZstdChunkBytes || level < kMinZstdLevel || level > kMaxZstdLevel)
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("zstd section: size {}, chunk {} or level {} out of range", size, chunkBytes, level));
  const uint64_t frames64 = (uint64_t{size} + chunkBytes - 1) / chunkBytes;
  if (frames64 > UINT32_MAX) return makeError(ErrorCode::CapacityExceeded, "zstd section: too many frames");
  const size_t frameCount = size_t(frames64);
  std::vector<std::vector<uint8_t>> frames(frameCount);
  std::vector<std::string> errors(frameCount);
  tbb::parallel_for(size_t{0}, frameCount, [&](size_t i) {
    const size_t begin = i * chunkBytes, n = std::min<size_t>(chunkBytes, size - begin);
    const std::unique_ptr<ZSTD_CCtx, CCtxFree> cctx(ZSTD_createCCtx());
    if (!cctx) {
      errors[i] = "cannot allocate a zstd compression context";
      return;
    }
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, level);
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);     // the reader requires it
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_contentSizeFlag, 1);  // and the declared size
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_dictIDFlag, 0);
    frames[i].resize(ZSTD_compressBound(n));
    const size_t got = ZSTD_compress2(cctx.get(), frames[i].data(), frames[i].size(), data + begin, n);
    if (ZSTD_isError(got)) {
      errors[i] = ZSTD_getErrorName(got);
      return;
    }
    frames[i].resize(got);
  });
  for (size_t i = 0; i < frameCount; ++i)
    if (!errors[i].empty())
      return makeError(ErrorCode::CapacityExceeded, fmt::format("zstd section frame {}: {}", i, errors[i]));
  const ZstdSectionHeader header{chunkBytes, uint32_t(frameCount), 0};
  size_t total = sizeof(header) + 4 * frameCount;
  for (const auto& f : frames) total += f.size();
  std::vector<uint8_t> out(total);
  std::memcpy(out.data(), &header, sizeof(header));
  size_t at = sizeof(header) + 4 * frameCount;
  for (size_t i = 0; i < frameCount; ++i) {
    const uint32_t n = uint32_t(frames[i].size());  // <= ZSTD_compressBound(16 MiB)
    std::memcpy(out.data() + sizeof(header) + 4 * i, &n, 4);
    std::memcpy(out.data() + at, frames[i].data(), n);
    at += n;
  }
  return out;
}

Result<StoredSection> storeSection(const std::vector<uint8_t>& bytes, int level) {
  StoredSection out;
  if (level <= 0 || bytes.size() < kMinCompressedSectionBytes) return out;
  Result<std::vector<uint8_t>> z = encodeZstdSection(bytes.data(), bytes.size(), level);
  if (!z) return z.error();
  if (z->size() <= bytes.size() - bytes.size() / 32) {
    out.encoding = kSectionZstd;
    out.stored = std::move(z.value());
  }
  return out;
}

Result<ZstdSection> ZstdSection::open(const uint8_t* stored, uint64_t storedSize, uint64_t decodedSize) {
  ZstdSectionHeader h;
  if (storedSize < sizeof(h))
    return malformed(fmt::format("zstd: {} stored bytes, smaller than the {}-byte header", storedSize, sizeof(h)));
  std::memcpy(&h, stored, sizeof(h));
  if (!std::has_single_bit(h.chunkBytes) || h.chunkBytes < kMinZstdChunkBytes || h.chunkBytes > kMaxZstdChunkBytes)
    return malformed(fmt::format("zstd: field 'chunkBytes' {} is not a power of two in [{}, {}]", h.chunkBytes,
                                 kMinZstdChunkBytes, kMaxZstdChunkBytes));
  if (h.reserved != 0) return malformed(fmt::format("zstd: field 'reserved' is {}, expected 0", h.reserved));
  if (decodedSize == 0) return malformed("zstd: a section of 0 decoded bytes is stored raw, never compressed");
  const uint64_t expectedFrames = (decodedSize - 1) / h.chunkBytes + 1;
  if (h.frameCount != expectedFrames)
    return malformed(fmt::format("zstd: field 'frameCount' {} differs from ceil({} decoded bytes / chunk {}) = {}",
                                 h.frameCount, decodedSize, h.chunkBytes, expectedFrames));
  const uint64_t tableEnd = sizeof(h) + uint64_t{h.frameCount} * 4;
  if (tableEnd > storedSize)
    return malformed(fmt::format("zstd: the table of {} frame sizes runs past the {} stored bytes", h.frameCount,
                                 storedSize));
  ZstdSection s;
  s.decodedSize_ = decodedSize;
  s.chunkBytes_ = h.chunkBytes;
  s.frames_.reserve(h.frameCount);
  uint64_t at = tableEnd;
  for (uint32_t i = 0; i < h.frameCount; ++i) {
    uint32_t n;
    std::memcpy(&n, stored + sizeof(h) + uint64_t{i} * 4, 4);
    if (n > storedSize - at)
      return malformed(fmt::format("zstd: frame {} ({} bytes at stored byte {}) runs past the {} stored bytes", i,
                                   n, at, storedSize));
    s.frames_.push_back({stored + at, n});
    at += n;
  }
  if (at != storedSize)
    return malformed(fmt::format("zstd: the frames end at stored byte {}, but the section stores {} bytes", at,
                                 storedSize));
  for (size_t i = 0; i < s.frames_.size(); ++i) {
    const Frame& f = s.frames_[i];
    const std::string where = fmt::format("zstd frame {} (stored bytes {}..{})", i, f.bytes - stored,
                                          f.bytes - stored + f.size);
    uint32_t magic = 0;
    if (f.size >= 4) std::memcpy(&magic, f.bytes, 4);
    if (f.size < 5 || magic != kZstdMagic)
      return malformed(fmt::format("{}: {}", where,
                                   (magic & kSkippableMagicMask) == kSkippableMagic
                                       ? "a skippable frame, which a pack never holds"
                                       : "not a zstd frame (no magic 0xFD2FB528)"));
    const uint8_t descriptor = f.bytes[4];
    if ((descriptor & 0x03) != 0) return malformed(where + ": has a dictionary ID; pack frames use no dictionary");
    if ((descriptor & 0x04) == 0) return malformed(where + ": has no content checksum, which a pack requires");
    const unsigned long long content = ZSTD_getFrameContentSize(f.bytes, f.size);
    if (content == ZSTD_CONTENTSIZE_ERROR) return malformed(where + ": damaged frame header");
    if (content == ZSTD_CONTENTSIZE_UNKNOWN) return malformed(where + ": declares no content size");
    if (content != s.frameDecodedBytes(i))
      return malformed(fmt::format("{}: declares {} decoded bytes, its share of the section is {}", where, content,
                                   s.frameDecodedBytes(i)));
    const size_t whole = ZSTD_findFrameCompressedSize(f.bytes, f.size);
    if (ZSTD_isError(whole))
      return malformed(fmt::format("{}: truncated or damaged ({})", where, ZSTD_getErrorName(whole)));
    if (whole != f.size)
      return malformed(fmt::format("{}: the frame ends after {} of its {} bytes (trailing bytes)", where, whole,
                                   f.size));
  }
  return s;
}

uint64_t ZstdSection::frameDecodedBytes(size_t i) const {
  const uint64_t begin = uint64_t{i} * chunkBytes_;
  return std::min<uint64_t>(chunkBytes_, decodedSize_ - begin);
}

Status ZstdSection::decodeFrame(size_t i, uint8_t* dst) const {
  const std::unique_ptr<ZSTD_DCtx, DCtxFree> dctx(ZSTD_createDCtx());
  if (!dctx) return makeError(ErrorCode::CapacityExceeded, "cannot allocate a zstd decompression context");
  const uint64_t expected = frameDecodedBytes(i);
  // Into exactly the declared size: a frame that would decode to more fails (destination too small) instead of
  // writing past it; one that decodes to fewer returns the short count.
  const size_t got = ZSTD_decompressDCtx(dctx.get(), dst, expected, frames_[i].bytes, frames_[i].size);
  if (ZSTD_isError(got))
    return malformed(fmt::format("zstd frame {}: {}", i, ZSTD_getErrorName(got)));
  if (got != expected)
    return malformed(fmt::format("zstd frame {}: decodes to {} bytes, it declares {}", i, got, expected));
  return {};
}

uint64_t ZstdSection::scratchBytes(uint64_t begin, uint64_t end) const {
  if (begin >= end) return 0;
  const size_t first = size_t(begin / chunkBytes_), last = size_t((end - 1) / chunkBytes_);
  uint64_t bytes = 0;
  if (begin % chunkBytes_ != 0 || frameDecodedBytes(first) > end - begin) bytes += frameDecodedBytes(first);
  if (last != first && (end % chunkBytes_ != 0 && end != decodedSize_)) bytes += frameDecodedBytes(last);
  return bytes;
}

Status ZstdSection::decode(uint64_t begin, uint64_t end, uint8_t* dst) const {
  if (begin > end || end > decodedSize_)
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("zstd: range [{}, {}) outside the {} decoded bytes", begin, end, decodedSize_));
  if (begin == end) return {};
  const size_t first = size_t(begin / chunkBytes_), last = size_t((end - 1) / chunkBytes_);
  std::vector<std::string> errors(last - first + 1);
  tbb::parallel_for(first, last + 1, [&](size_t i) {
    const uint64_t frameBegin = uint64_t{i} * chunkBytes_, frameEnd = frameBegin + frameDecodedBytes(i);
    Status s;
    if (frameBegin >= begin && frameEnd <= end) {
      s = decodeFrame(i, dst + (frameBegin - begin));
    } else {  // the frame straddles an end of the range: decode it whole, keep the overlap
      std::vector<uint8_t> scratch(frameEnd - frameBegin);
      s = decodeFrame(i, scratch.data());
      if (s) {
        const uint64_t from = std::max(begin, frameBegin), to = std::min(end, frameEnd);
        std::memcpy(dst + (from - begin), scratch.data() + (from - frameBegin), to - from);
      }
    }
    if (!s) errors[i - first] = s.error().message;
  });
  for (const std::string& e : errors)
    if (!e.empty()) return malformed(e);
  return {};
}

}  // namespace visbuf::pack
