// Section encodings of the pack (pack_format.h: SectionEntry::encoding, ZstdSectionHeader): zstd supercompression
// of a section's bytes in independent frames of a fixed decoded size, so that frames compress and decode in
// parallel and a reader can decode any byte range straight into its destination.
//
// The stored bytes are untrusted: ZstdSection::open checks the header, the frame table and every frame's header
// against the decoded size the section table declares before anything is decoded, and decode() refuses a frame
// that decodes to other than its declared bytes or fails its content checksum. Decoding never writes outside the
// destination range and allocates at most one chunk (kMaxZstdChunkBytes) of scratch per frame that straddles the
// range's ends; the caller bounds the decoded size (PackReadOptions::maxDecodedBytes) before allocating it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "visbuf/core/result.h"

namespace visbuf::pack {

// Decoded bytes per frame the writer uses: 1 MiB gives a 17 MB texel section 17 frames to decode in parallel, and
// costs about 0.5 % of the ratio against one frame (measured on DamagedHelmet's BC blocks, level 9).
inline constexpr uint32_t kZstdChunkBytes = uint32_t{1} << 20;
// zstd levels the writer accepts (PackWriteOptions::compressionLevel); the default balances bake time (about
// 1 s of one core for 17 MB at level 9, 22 s at 19) against size (level 19 saves another 6 %).
inline constexpr int kMinZstdLevel = 1;
inline constexpr int kMaxZstdLevel = 19;
inline constexpr int kDefaultZstdLevel = 9;

// The stored bytes of a kSectionZstd section holding `data` (`size` > 0 bytes): frames of `chunkBytes` decoded
// bytes compressed in parallel at `level`. The output depends only on the input, level, chunk size and the zstd
// library version, never on the thread count. CapacityExceeded when zstd cannot allocate its context.
Result<std::vector<uint8_t>> encodeZstdSection(const uint8_t* data, size_t size, int level,
                                               uint32_t chunkBytes = kZstdChunkBytes);

// Sections below this size are stored raw: a frame's header, checksum and table entry (about 20 bytes) and a
// decoder call would outweigh what compression saves.
inline constexpr uint64_t kMinCompressedSectionBytes = 4096;

// How the writer stores one section: `encoding` kSectionZstd with its stored bytes in `stored` when `level` > 0,
// the section holds at least kMinCompressedSectionBytes and the frames save at least 1/32 of its bytes (less
// would not repay the decode); else kSectionRaw with `stored` empty (the caller writes its bytes as they are).
struct StoredSection {
  uint32_t encoding = 0;  // kSectionRaw
  std::vector<uint8_t> stored;
};
Result<StoredSection> storeSection(const std::vector<uint8_t>& bytes, int level);

// A checked kSectionZstd section (pointers into the caller's stored bytes, which must outlive it).
class ZstdSection {
 public:
  // Checks, without decoding: the header (chunk size a power of two in [kMinZstdChunkBytes, kMaxZstdChunkBytes],
  // frame count = ceil(decodedSize / chunkBytes), reserved 0), the frame table (it and the frames fill
  // storedSize exactly, overflow-safe), and per frame: the zstd magic (no skippable frame), no dictionary ID, the
  // content checksum flag, a declared content size equal to the frame's share of decodedSize, and exactly one
  // whole frame in its byte range (not truncated, no trailing bytes). MalformedInput naming the frame otherwise.
  static Result<ZstdSection> open(const uint8_t* stored, uint64_t storedSize, uint64_t decodedSize);

  // Decodes the decoded bytes [begin, end) into dst[0, end - begin): the frames that overlap the range, in
  // parallel; frames wholly inside it decode straight into dst. MalformedInput naming the first failing frame
  // (a damaged block, a content checksum mismatch, more or fewer bytes than declared); dst is then partly written.
  Status decode(uint64_t begin, uint64_t end, uint8_t* dst) const;

  uint64_t decodedSize() const { return decodedSize_; }
  uint32_t chunkBytes() const { return chunkBytes_; }
  size_t frameCount() const { return frames_.size(); }
  // The most scratch one decode() call allocates besides dst (a chunk for each of the range's two end frames).
  uint64_t scratchBytes(uint64_t begin, uint64_t end) const;

 private:
  struct Frame {
    const uint8_t* bytes;
    uint32_t size;
  };
  Status decodeFrame(size_t i, uint8_t* dst) const;  // the whole frame i, into its decoded size at dst
  uint64_t frameDecodedBytes(size_t i) const;
  std::vector<Frame> frames_;
  uint64_t decodedSize_ = 0;
  uint32_t chunkBytes_ = 0;
};

}  // namespace visbuf::pack
