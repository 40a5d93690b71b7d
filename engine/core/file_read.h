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
#include <memory>
#include <optional>
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
//   IoError: open / read failures, or a file that shrank or changed while being read (its size, modification or
//            change time differ between the fstat() before and the one after the read: written in place by
//            another program meanwhile; the bytes read are then discarded).
Result<std::vector<uint8_t>> readRegularFile(const std::string& path, const FileReadOptions& options = {});

// A private copy of a whole regular file, read once (the checks and errors of readRegularFile()): nothing parsed
// from it can change afterwards, whatever another program does to the file. Unlike a mapping, a file truncated
// or overwritten in place while it is used cannot raise SIGBUS or change bytes already checked.
struct SnapshotUnmap {
  size_t bytes = 0;
  void operator()(uint8_t* p) const;
};
struct FileSnapshot {
  // Anonymous memory mapped with MAP_POPULATE (its pages made in one call, not one fault each); null when empty.
  std::unique_ptr<uint8_t[], SnapshotUnmap> bytes;
  size_t size = 0;
  const uint8_t* data() const { return bytes.get(); }
};
Result<FileSnapshot> readFileSnapshot(const std::string& path, const FileReadOptions& options = {});

// Opens the regular file at `path` as readRegularFile() does (non-blocking, O_NOFOLLOW with `noFollow`, fstat on
// the descriptor) and returns the descriptor, which the caller closes; `size` gets the file's size. The same
// errors as readRegularFile() but for the budget and reading.
Result<int> openRegularFile(const std::string& path, bool noFollow, uint64_t* size);

// The first `count` bytes (fewer when the file is shorter) of a regular file; an error as readRegularFile()
// for anything else. Never blocks.
Result<std::vector<uint8_t>> readFilePrefix(const std::string& path, size_t count);

// ---- the inputs of this process (no output is ever written over one) --------------------------------------
// A program that reads inputs and writes outputs (the visbuf command line: one command a process) turns the
// input log on once, before reading anything. From then on every file opened by the functions above (and by
// MappedFile) is recorded by identity -- device and inode of the file opened, plus those of the path itself
// where it is a symbolic link -- and commitFile() (core/temp_file.h), through which every output of the engine
// and the tools is renamed into place, refuses a target that is one of them: the same file, a hard link of it, a
// symbolic link to it, or the link an input was opened through. Files this process wrote itself (committed
// outputs) are not recorded when it reads them back. Off (the default, for library users and tests), nothing is
// recorded and nothing is refused. Thread-safe.
struct InputFileRecord {
  uint64_t device = 0;
  uint64_t inode = 0;
  std::string path;  // as opened
  std::string role;  // what it is to the command ("scene.gltf: buffer 0"), empty when only read
};

void enableInputLog();
// Turns the log off and forgets every record (a host that runs several commands in one process, and tests).
void disableInputLog();
bool inputLogEnabled();
// Records `path` as an input even before (or without) reading it: a file the command was given or that an input
// references (a glTF's buffers and images), so that an output aimed at it is refused up front and also when the
// file is never read (bake --no-textures). `role` says what it is in messages. A path that cannot be stat()ed is
// ignored (it cannot be overwritten by an output that is checked later: that output would create it).
void noteInputFile(const std::string& path, const std::string& role);
// The recorded input that writing to `path` would replace or alias: `path` (following symbolic links) or the
// link itself has the identity of an input. nullopt when the log is off or `path` does not exist.
std::optional<InputFileRecord> findInputFile(const std::string& path);
// Marks the file now at `path` as written by this process (not an input when read back).
void noteOutputFile(const std::string& path);
// Every input recorded so far, in the order recorded.
std::vector<InputFileRecord> inputFiles();

}  // namespace visbuf
