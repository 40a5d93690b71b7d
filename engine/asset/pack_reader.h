// Reads a visbuf pack (pack_format.h, docs/pack-format.md) into a Scene.
//
// The reader trusts nothing in the file: every offset, count, size and index is checked (with overflow-safe
// arithmetic) before a byte is touched, so a damaged or hostile file gives an Error, never an assert, crash,
// out-of-bounds read or an allocation larger than 64 times the file (the geometry codecs' largest expansion) plus
// the decoded size of its zstd sections, which PackReadOptions::maxDecodedBytes bounds.
// Messages start with the path (or label) and name
// the section, record and field, e.g.
//   "pack.vbp: section 'indices' runs past the end of the file (offset 1234, size 5678, file 4000)".
// Error codes: FileNotFound / IoError (cannot read), Unsupported (another format version), MalformedInput
// (everything else: bad magic, truncation, checksum mismatch, out-of-range or non-finite values),
// CapacityExceeded (out of memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// Largest pack file readPack() reads (into memory: callers that know the memory they may use check the file's size
// against it first, as the command line does).
inline constexpr uint64_t kMaxPackFileBytes = uint64_t{1} << 40;

// Default PackReadOptions::maxDecodedBytes: 4 GiB, as the glTF import's memory budget.
inline constexpr uint64_t kDefaultPackDecodedBytes = uint64_t{4} << 30;

struct PackReadOptions {
  // The most bytes the pack's zstd sections may decode to together (their declared sizes, checked before any is
  // allocated): a compressed section can declare thousands of times its stored size, so this, not the file's
  // size, bounds what reading a compressed pack allocates. CapacityExceeded beyond it.
  uint64_t maxDecodedBytes = kDefaultPackDecodedBytes;
};

// What reading a pack cost besides the Scene it returns (for load statistics).
struct PackReadStats {
  uint64_t fileBytes = 0;         // the pack's size (read once into private memory by readPack, freed on return)
  uint64_t largestSection = 0;    // bytes of the largest section as stored
  uint64_t peakScratchBytes = 0;  // the largest transient decode buffer (quantised vertices of one mesh); the
                                  // Scene's own decoded geometry is not counted
};

// Reads the pack file at `path` once into private memory (core/file_read.h: readFileSnapshot) and parses that
// copy; the copy is freed on return. The result passes validateScene(). `stats` (may be null) gets the read's
// figures.
//
// A pack changed by another program while it is read -- truncated, extended or overwritten in place -- gives an
// Error (IoError: "changed while it was being read" / "shrank", or MalformedInput: a checksum or size mismatch),
// never SIGBUS and never a scene with bytes from after the checksum check: the checksums are verified on the copy
// that is decoded. Once readPack has returned, the file is not read again.
Result<Scene> readPack(const std::string& path, PackReadStats* stats = nullptr);
Result<Scene> readPack(const std::string& path, const PackReadOptions& options, PackReadStats* stats = nullptr);

// Parses pack bytes held in memory (`size` bytes at `data`); `label` starts every error message.
Result<Scene> parsePack(const uint8_t* data, size_t size, const std::string& label, PackReadStats* stats = nullptr);
Result<Scene> parsePack(const uint8_t* data, size_t size, const std::string& label, const PackReadOptions& options,
                        PackReadStats* stats = nullptr);

// True when the file at `path` can be opened and starts with the pack magic "VBPK".
bool isPackFile(const std::string& path);

}  // namespace visbuf
