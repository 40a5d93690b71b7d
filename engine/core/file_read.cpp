#include "visbuf/core/file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>

namespace visbuf {

namespace {

// Closes the descriptor on every path out.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

int openNonBlocking(const std::string& path, bool noFollow) {
  int flags = O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
  if (noFollow) flags |= O_NOFOLLOW;
  int fd = -1;
  do {
    fd = ::open(path.c_str(), flags);
  } while (fd < 0 && errno == EINTR);
  return fd;
}

FileKind kindOf(mode_t mode) {
  if (S_ISREG(mode)) return FileKind::Regular;
  if (S_ISDIR(mode)) return FileKind::Directory;
  if (S_ISFIFO(mode)) return FileKind::Fifo;
  if (S_ISSOCK(mode)) return FileKind::Socket;
  if (S_ISCHR(mode)) return FileKind::CharDevice;
  if (S_ISBLK(mode)) return FileKind::BlockDevice;
  if (S_ISLNK(mode)) return FileKind::Symlink;
  return FileKind::Other;
}

// The kind of a path that open() refused: a socket cannot be opened (ENXIO) and O_NOFOLLOW refuses a link
// (ELOOP); lstat tells those apart from a missing file without opening anything.
FileKind kindOfUnopenable(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return FileKind::Missing;
  const FileKind kind = kindOf(st.st_mode);
  return kind == FileKind::Regular || kind == FileKind::Directory ? FileKind::Missing : kind;
}

Error notRegular(const std::string& path, FileKind kind) {
  return makeError(ErrorCode::InvalidArgument, path + ": not a regular file (" + fileKindName(kind) +
                                                "); only regular files are read");
}

// Opens `path` and checks that it is a regular file; `size` gets its size.
Result<int> openRegular(const std::string& path, bool noFollow, uint64_t* size) {
  const int fd = openNonBlocking(path, noFollow);
  if (fd < 0) {
    const int err = errno;
    const FileKind kind = kindOfUnopenable(path);
    if (kind != FileKind::Missing) return notRegular(path, kind);
    if (err == ENOENT || err == ENOTDIR) return makeError(ErrorCode::FileNotFound, path + ": file not found");
    return makeError(ErrorCode::IoError, path + ": cannot open for reading (" + std::strerror(err) + ")");
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int err = errno;
    ::close(fd);
    return makeError(ErrorCode::IoError, path + ": cannot stat (" + std::strerror(err) + ")");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return notRegular(path, kindOf(st.st_mode));
  }
  *size = static_cast<uint64_t>(st.st_size);
  return fd;
}

// Reads up to `count` bytes at the current offset; returns the number read (< count only at end of file).
Result<size_t> readUpTo(int fd, uint8_t* out, size_t count, const std::string& path) {
  size_t done = 0;
  while (done < count) {
    const ssize_t n = ::read(fd, out + done, count - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return makeError(ErrorCode::IoError, path + ": read failed (" + std::strerror(errno) + ")");
    }
    if (n == 0) break;
    done += static_cast<size_t>(n);
  }
  return done;
}

}  // namespace

const char* fileKindName(FileKind kind) {
  switch (kind) {
    case FileKind::Missing: return "missing";
    case FileKind::Regular: return "a regular file";
    case FileKind::Directory: return "a directory";
    case FileKind::Fifo: return "a FIFO";
    case FileKind::Socket: return "a socket";
    case FileKind::CharDevice: return "a character device";
    case FileKind::BlockDevice: return "a block device";
    case FileKind::Symlink: return "a symbolic link";
    case FileKind::Other: return "not a regular file";
  }
  return "unknown";
}

FileKind probeFile(const std::string& path, uint64_t* size, bool noFollow) {
  const int raw = openNonBlocking(path, noFollow);
  if (raw < 0) return kindOfUnopenable(path);
  Fd fd(raw);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return FileKind::Missing;
  if (size && S_ISREG(st.st_mode)) *size = static_cast<uint64_t>(st.st_size);
  return kindOf(st.st_mode);
}

Result<int> openRegularFile(const std::string& path, bool noFollow, uint64_t* size) {
  return openRegular(path, noFollow, size);
}

Result<std::vector<uint8_t>> readRegularFile(const std::string& path, const FileReadOptions& options) {
  uint64_t size = 0;
  Result<int> opened = openRegular(path, options.noFollow, &size);
  if (!opened) return opened.error();
  Fd fd(*opened);
  if (size > options.maxBytes) {
    return makeError(ErrorCode::CapacityExceeded, path + ": file of " + std::to_string(size) +
                                                      " bytes exceeds the read budget of " +
                                                      std::to_string(options.maxBytes) + " bytes");
  }
  std::vector<uint8_t> bytes;
  try {
    bytes.resize(static_cast<size_t>(size));
  } catch (const std::bad_alloc&) {
    return makeError(ErrorCode::CapacityExceeded, path + ": out of memory reading " + std::to_string(size) + " bytes");
  }
  Result<size_t> got = readUpTo(fd.get(), bytes.data(), bytes.size(), path);
  if (!got) return got.error();
  if (*got != bytes.size()) {
    return makeError(ErrorCode::IoError, path + ": file shrank while being read (" + std::to_string(*got) + " of " +
                                             std::to_string(size) + " bytes)");
  }
  return bytes;
}

Result<std::vector<uint8_t>> readFilePrefix(const std::string& path, size_t count) {
  uint64_t size = 0;
  Result<int> opened = openRegular(path, false, &size);
  if (!opened) return opened.error();
  Fd fd(*opened);
  std::vector<uint8_t> bytes(static_cast<size_t>(std::min<uint64_t>(count, size)));
  Result<size_t> got = readUpTo(fd.get(), bytes.data(), bytes.size(), path);
  if (!got) return got.error();
  bytes.resize(*got);
  return bytes;
}

}  // namespace visbuf
