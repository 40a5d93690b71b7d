#include "visbuf/core/mapped_file.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <utility>

namespace visbuf {

Result<MappedFile> MappedFile::open(const std::string& path, const FileReadOptions& options) {
  uint64_t size = 0;
  Result<int> fd = openRegularFile(path, options.noFollow, &size);
  if (!fd) return fd.error();
  if (size > options.maxBytes || size > std::numeric_limits<size_t>::max()) {
    ::close(*fd);
    return makeError(ErrorCode::CapacityExceeded, path + ": file of " + std::to_string(size) +
                                                      " bytes exceeds the read budget of " +
                                                      std::to_string(options.maxBytes) + " bytes");
  }
  MappedFile file;
  if (size > 0) {
    void* p = ::mmap(nullptr, static_cast<size_t>(size), PROT_READ, MAP_PRIVATE, *fd, 0);
    if (p == MAP_FAILED) {
      const int err = errno;
      ::close(*fd);
      return makeError(err == ENOMEM ? ErrorCode::CapacityExceeded : ErrorCode::IoError,
                       path + ": cannot map " + std::to_string(size) + " bytes (" + std::strerror(err) + ")");
    }
    file.data_ = p;
    file.size_ = static_cast<size_t>(size);
  }
  ::close(*fd);  // the mapping stays valid without the descriptor
  return file;
}

MappedFile& MappedFile::operator=(MappedFile&& o) noexcept {
  if (this != &o) {
    reset();
    data_ = std::exchange(o.data_, nullptr);
    size_ = std::exchange(o.size_, 0);
  }
  return *this;
}

void MappedFile::reset() {
  if (data_ != nullptr) ::munmap(data_, size_);
  data_ = nullptr;
  size_ = 0;
}

}  // namespace visbuf
