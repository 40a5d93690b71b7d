#include "visbuf/core/file_read.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <limits>
#include <mutex>
#include <new>
#include <set>
#include <utility>

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

// ---- the input log (file_read.h) ----
using FileId = std::pair<uint64_t, uint64_t>;  // (st_dev, st_ino)

struct InputLog {
  std::mutex mutex;
  std::vector<InputFileRecord> inputs;
  std::set<FileId> inputIds;
  std::set<FileId> outputIds;  // files this process committed
};
std::atomic<bool> gInputLogOn{false};
InputLog& inputLog() {
  static InputLog log;
  return log;
}
FileId idOf(const struct stat& st) { return {uint64_t(st.st_dev), uint64_t(st.st_ino)}; }

// Records the file open as `st` (and the link `path` is, when it is one) unless this process wrote it.
void recordInput(const std::string& path, const struct stat& st, const std::string& role) {
  if (!gInputLogOn.load(std::memory_order_acquire)) return;
  InputLog& log = inputLog();
  std::lock_guard<std::mutex> lock(log.mutex);
  const FileId id = idOf(st);
  if (log.outputIds.count(id) != 0) return;
  auto add = [&](const FileId& fid) {
    if (log.inputIds.insert(fid).second) {
      log.inputs.push_back({fid.first, fid.second, path, role});
    } else if (!role.empty()) {  // a role given later (noteInputFile after a read) names it in messages
      for (InputFileRecord& r : log.inputs)
        if (r.device == fid.first && r.inode == fid.second && r.role.empty()) r.role = role;
    }
  };
  add(id);
  struct stat linkStat {};
  if (::lstat(path.c_str(), &linkStat) == 0 && S_ISLNK(linkStat.st_mode)) add(idOf(linkStat));
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
  recordInput(path, st, {});
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
  if (S_ISREG(st.st_mode)) recordInput(path, st, {});
  if (size && S_ISREG(st.st_mode)) *size = static_cast<uint64_t>(st.st_size);
  return kindOf(st.st_mode);
}

Result<int> openRegularFile(const std::string& path, bool noFollow, uint64_t* size) {
  return openRegular(path, noFollow, size);
}

namespace {

// The fstat() fields that change when a file is written, truncated or replaced in place.
bool sameVersion(const struct stat& a, const struct stat& b) {
  return a.st_size == b.st_size && a.st_mtim.tv_sec == b.st_mtim.tv_sec && a.st_mtim.tv_nsec == b.st_mtim.tv_nsec &&
         a.st_ctim.tv_sec == b.st_ctim.tv_sec && a.st_ctim.tv_nsec == b.st_ctim.tv_nsec;
}

// Opens `path` under `options`, checks the budget and reads the whole file into the buffer that `allocate(size)`
// returns (null: out of memory); IoError when it shrank or changed while being read.
template <typename Allocate>
Status readWhole(const std::string& path, const FileReadOptions& options, Allocate&& allocate) {
  uint64_t size = 0;
  Result<int> opened = openRegular(path, options.noFollow, &size);
  if (!opened) return opened.error();
  Fd fd(*opened);
  if (size > options.maxBytes || size > std::numeric_limits<size_t>::max()) {
    return makeError(ErrorCode::CapacityExceeded, path + ": file of " + std::to_string(size) +
                                                      " bytes exceeds the read budget of " +
                                                      std::to_string(options.maxBytes) + " bytes");
  }
  struct stat before {};
  if (::fstat(fd.get(), &before) != 0)
    return makeError(ErrorCode::IoError, path + ": cannot stat (" + std::strerror(errno) + ")");
  uint8_t* out = nullptr;
  try {
    out = allocate(static_cast<size_t>(size));
  } catch (const std::bad_alloc&) {
    out = nullptr;
  }
  if (out == nullptr && size > 0)
    return makeError(ErrorCode::CapacityExceeded, path + ": out of memory reading " + std::to_string(size) + " bytes");
  Result<size_t> got = readUpTo(fd.get(), out, static_cast<size_t>(size), path);
  if (!got) return got.error();
  if (*got != size) {
    return makeError(ErrorCode::IoError, path + ": file shrank while being read (" + std::to_string(*got) + " of " +
                                             std::to_string(size) + " bytes)");
  }
  struct stat after {};
  if (::fstat(fd.get(), &after) != 0 || !sameVersion(before, after)) {
    return makeError(ErrorCode::IoError, path + ": the file changed while it was being read (written, truncated or "
                                                "extended in place by another program); nothing read from it is used");
  }
  return {};
}

}  // namespace

Result<std::vector<uint8_t>> readRegularFile(const std::string& path, const FileReadOptions& options) {
  std::vector<uint8_t> bytes;
  Status s = readWhole(path, options, [&](size_t size) {
    bytes.resize(size);
    return bytes.data();
  });
  if (!s) return s.error();
  return bytes;
}

Result<FileSnapshot> readFileSnapshot(const std::string& path, const FileReadOptions& options) {
  FileSnapshot snapshot;
  Status s = readWhole(path, options, [&](size_t size) {
    if (size == 0) return static_cast<uint8_t*>(nullptr);
    void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_POPULATE, -1, 0);
    if (p == MAP_FAILED) return static_cast<uint8_t*>(nullptr);
    snapshot.bytes = std::unique_ptr<uint8_t[], SnapshotUnmap>(static_cast<uint8_t*>(p), SnapshotUnmap{size});
    snapshot.size = size;
    return snapshot.bytes.get();
  });
  if (!s) return s.error();
  return snapshot;
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

void SnapshotUnmap::operator()(uint8_t* p) const {
  if (p != nullptr) ::munmap(p, bytes);
}

void enableInputLog() { gInputLogOn.store(true, std::memory_order_release); }
void disableInputLog() {
  gInputLogOn.store(false, std::memory_order_release);
  InputLog& log = inputLog();
  std::lock_guard<std::mutex> lock(log.mutex);
  log.inputs.clear();
  log.inputIds.clear();
  log.outputIds.clear();
}
bool inputLogEnabled() { return gInputLogOn.load(std::memory_order_acquire); }

void noteInputFile(const std::string& path, const std::string& role) {
  if (!inputLogEnabled() || path.empty()) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    // A dangling link: the link itself is still the input's name, and writing through it creates the target.
    if (::lstat(path.c_str(), &st) != 0) return;
  }
  recordInput(path, st, role);
}

std::optional<InputFileRecord> findInputFile(const std::string& path) {
  if (!inputLogEnabled()) return std::nullopt;
  struct stat target {}, linkStat {};
  const bool hasTarget = ::stat(path.c_str(), &target) == 0;
  const bool hasLink = ::lstat(path.c_str(), &linkStat) == 0;
  InputLog& log = inputLog();
  std::lock_guard<std::mutex> lock(log.mutex);
  for (const InputFileRecord& r : log.inputs) {
    const FileId id{r.device, r.inode};
    if ((hasTarget && idOf(target) == id) || (hasLink && idOf(linkStat) == id)) return r;
  }
  return std::nullopt;
}

void noteOutputFile(const std::string& path) {
  if (!inputLogEnabled()) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return;
  InputLog& log = inputLog();
  std::lock_guard<std::mutex> lock(log.mutex);
  log.outputIds.insert(idOf(st));
}

std::vector<InputFileRecord> inputFiles() {
  InputLog& log = inputLog();
  std::lock_guard<std::mutex> lock(log.mutex);
  return log.inputs;
}

}  // namespace visbuf
