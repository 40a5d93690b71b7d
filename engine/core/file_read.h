// Reading input files that may be hostile (docs/security.md): only regular files are read, they are opened
// without blocking, and their size is checked against a budget before anything is allocated.
//
// Every function opens the path with O_RDONLY | O_NONBLOCK | O_CLOEXEC (so a FIFO without a writer, a
// character device or a terminal never makes open() or read() wait), then fstat()s the open descriptor and
// refuses anything that is not a regular file (FIFO, socket, device, directory) before reading a byte.
// Checking the descriptor, not the name, leaves no window in which the path can be swapped.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "visbuf/core/result.h"

namespace visbuf {

// Default size budget of readRegularFile(): 4 GiB minus one page.
inline constexpr uint64_t kDefaultMaxFileBytes = (uint64_t{4} << 30) - 4096;

struct FileReadOptions {
  uint64_t maxBytes = kDefaultMaxFileBytes;  // files larger than this are refused before allocating
  bool noFollow = false;                     // O_NOFOLLOW: refuse a symbolic link as the last component
};

// What kind of file a path names, as fstat() on a non-blocking descriptor sees it.
enum class FileKind { Missing, Regular, Directory, Fifo, Socket, CharDevice, BlockDevice, Symlink, Other };

// "a FIFO", "a directory", ... for messages.
const char* fileKindName(FileKind kind);

// Opens without blocking and fstat()s. Missing when the path cannot be opened at all (missing, no
// permission, a dangling link); `size` (may be null) gets the size of a regular file.
FileKind probeFile(const std::string& path, uint64_t* size = nullptr, bool noFollow = false);

// Reads the whole regular file at `path`. Errors, each starting with `path`:
//   FileNotFound: missing;
//   InvalidArgument: not a regular file ("<path>: not a regular file (a FIFO); only regular files are read");
//   CapacityExceeded: larger than options.maxBytes (the message gives both sizes), or out of memory;
//   IoError: open / read failures, or a file that shrank while being read.
Result<std::vector<uint8_t>> readRegularFile(const std::string& path, const FileReadOptions& options = {});

// Opens the regular file at `path` as readRegularFile() does (non-blocking, O_NOFOLLOW with `noFollow`, fstat on
// the descriptor) and returns the descriptor, which the caller closes; `size` gets the file's size. The same
// errors as readRegularFile() but for the budget and reading.
Result<int> openRegularFile(const std::string& path, bool noFollow, uint64_t* size);

// The first `count` bytes (fewer when the file is shorter) of a regular file; an error as readRegularFile()
// for anything else. Never blocks.
Result<std::vector<uint8_t>> readFilePrefix(const std::string& path, size_t count);

}  // namespace visbuf
