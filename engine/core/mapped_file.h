// A whole regular file mapped read-only into memory (POSIX mmap, PROT_READ, MAP_PRIVATE), opened under the rules
// of core/file_read.h: non-blocking open, only regular files (checked on the descriptor), optional O_NOFOLLOW, and
// a size budget checked before mapping. The mapping uses the size fstat() reported at open.
//
// Remaining risk: if another process truncates the file in place while it is mapped, touching a page past the
// new end raises SIGBUS, and bytes overwritten in place show through the mapping after any check made on them.
// Replacing the file by rename (as every visbuf writer does) is safe: the mapping keeps the old file. Inputs that
// another program may change (packs: readPack) are read as a private copy (readFileSnapshot) instead.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "visbuf/core/file_read.h"
#include "visbuf/core/result.h"

namespace visbuf {

class MappedFile {
 public:
  // Errors as readRegularFile(): FileNotFound, InvalidArgument (not a regular file), CapacityExceeded (over
  // options.maxBytes, or larger than the address space), IoError (open, fstat or mmap failed).
  static Result<MappedFile> open(const std::string& path, const FileReadOptions& options = {});

  MappedFile() = default;
  ~MappedFile() { reset(); }
  MappedFile(MappedFile&& o) noexcept { *this = std::move(o); }
  MappedFile& operator=(MappedFile&& o) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  // The file's bytes; null for an empty file (nothing is mapped).
  const uint8_t* data() const { return static_cast<const uint8_t*>(data_); }
  size_t size() const { return size_; }
  void reset();

 private:
  void* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace visbuf
