// Temporary files of atomic writes ("write ".NAME.tmp<pid>.<n>" next to NAME, fsync, rename"): what is left
// behind when the writer is interrupted. No Vulkan, no allocation in the signal path.
#pragma once

#include <filesystem>
#include <string>

#include "visbuf/core/result.h"

namespace visbuf {

struct TempSlot;

// While alive, SIGINT / SIGTERM / SIGHUP unlink `path` before the process ends with the signal's default
// action (exit status 128 + signal). Construct it before creating the file (no instant exists where the file is
// on disk unregistered) and keep it until the rename. The handler is installed only for signals whose
// disposition is the default one: a host's own handler, or SIG_IGN, is left alone (and the host then owns the
// cleanup); it is restored when the last guard of the process ends. At most 8 guards at a time are tracked
// (more still work, without the signal cleanup); a path of PATH_MAX bytes or more is not tracked.
class TempFileGuard {
 public:
  explicit TempFileGuard(const std::string& path);
  ~TempFileGuard();
  TempFileGuard(const TempFileGuard&) = delete;
  TempFileGuard& operator=(const TempFileGuard&) = delete;

 private:
  TempSlot* slot_ = nullptr;
};

// Removes the ".<name>.tmp<pid>.<n>" files next to `target` that a writer which no longer exists left behind
// (killed with SIGKILL, or by a crash or power loss, where no handler runs): regular files of this user whose
// <pid> is no live process (kill(pid, 0) fails with ESRCH). Files of live processes, of other users (kill:
// EPERM), and of this process are kept. Best effort: errors are ignored.
void removeStaleTempFiles(const std::filesystem::path& target);

// The last step of every atomic write: renames the finished temporary file `tmp` onto `path` (same folder), and
// removes `tmp` on failure. Every output of the engine and the tools goes through here, so this is where "no
// output replaces an input" holds: while the input log is on (core/file_read.h), a `path` that is an input of
// this process (the same file, a hard link, a symbolic link to it, or the link it was opened through) is refused
// with InvalidArgument ("<path>: is an input of this command (<what>); refused"), nothing is renamed and `tmp`
// is removed. A committed file is marked as this process's output (reading it back does not make it an input).
Status commitFile(const std::string& tmp, const std::string& path);

}  // namespace visbuf
