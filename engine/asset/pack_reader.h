// Reads a visbuf pack (pack_format.h, docs/pack-format.md) into a Scene.
//
// The reader trusts nothing in the file: every offset, count, size and index is checked (with overflow-safe
// arithmetic) before a byte is touched, so a damaged or hostile file gives an Error, never an assert, crash,
// out-of-bounds read or an allocation larger than the file. Messages start with the path (or label) and name
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

// Reads the pack file at `path`. The result passes validateScene().
Result<Scene> readPack(const std::string& path);

// Parses pack bytes held in memory (`size` bytes at `data`); `label` starts every error message.
Result<Scene> parsePack(const uint8_t* data, size_t size, const std::string& label);

// True when the file at `path` can be opened and starts with the pack magic "VBPK".
bool isPackFile(const std::string& path);

}  // namespace visbuf
