// Temporary files of atomic writes (temp_file.h): removed on SIGINT / SIGTERM / SIGHUP, and when a dead writer
// left them.
#include "visbuf/core/temp_file.h"

#include <fmt/format.h>

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <limits>
#include <mutex>
#include <string_view>
#include <system_error>

#include "visbuf/core/file_read.h"

namespace visbuf {

// The temporary files being written, for the signal handler: fixed buffers, so that the handler neither
// allocates nor locks (async-signal-safe: it only reads lock-free atomics and calls unlink, signal, raise).
// One slot per concurrent writer of this process; state 0 free, 1 being filled, 2 active (unlinked on a signal).
struct TempSlot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};

namespace {

constexpr int kTempSlots = 8;
TempSlot gTempSlots[kTempSlots];
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots' state");

constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP};
constexpr size_t kSignalCount = sizeof(kCleanupSignals) / sizeof(kCleanupSignals[0]);

extern "C" void removeTempFilesOnSignal(int sig) {
  const int savedErrno = errno;
  for (TempSlot& slot : gTempSlots)
    if (slot.state.load() == 2) ::unlink(slot.path);
  // Then the signal's own default action (the process ends as the signal asked, exit status 128 + sig): the
  // signal is blocked while this handler runs, so it is delivered again as soon as the handler returns.
  ::signal(sig, SIG_DFL);
  ::raise(sig);
  errno = savedErrno;
}

// The handler is installed while at least one temporary file is being written, and only for signals whose disposition
// is the default one: a host's own handler, or SIG_IGN, is left alone (and the host then owns the cleanup).
std::mutex gHandlerMutex;
int gWriters = 0;
struct sigaction gPrevious[kSignalCount];
bool gInstalled[kSignalCount] = {};

}  // namespace

TempFileGuard::TempFileGuard(const std::string& path) {
  {
    std::lock_guard<std::mutex> lock(gHandlerMutex);
    if (gWriters++ == 0) {
      for (size_t i = 0; i < kSignalCount; ++i) {
        struct sigaction current {};
        gInstalled[i] = false;
        if (::sigaction(kCleanupSignals[i], nullptr, &current) != 0) continue;
        if ((current.sa_flags & SA_SIGINFO) != 0 || current.sa_handler != SIG_DFL) continue;
        struct sigaction ours {};
        ours.sa_handler = removeTempFilesOnSignal;
        sigemptyset(&ours.sa_mask);
        for (int other : kCleanupSignals) sigaddset(&ours.sa_mask, other);  // one handler run at a time
        ours.sa_flags = 0;
        if (::sigaction(kCleanupSignals[i], &ours, &gPrevious[i]) == 0) gInstalled[i] = true;
      }
    }
  }
  if (path.size() >= PATH_MAX) return;  // (open() would fail with ENAMETOOLONG anyway)
  for (TempSlot& slot : gTempSlots) {
    int expected = 0;
    if (slot.state.compare_exchange_strong(expected, 1)) {
      std::memcpy(slot.path, path.c_str(), path.size() + 1);
      slot.state.store(2);
      slot_ = &slot;
      break;
    }
  }
}
TempFileGuard::~TempFileGuard() {
  if (slot_) slot_->state.store(0);
  std::lock_guard<std::mutex> lock(gHandlerMutex);
  if (--gWriters == 0) {
    for (size_t i = 0; i < kSignalCount; ++i) {
      if (!gInstalled[i]) continue;
      struct sigaction current {};
      // Restored only where ours is still installed (a host may have installed its own meanwhile).
      if (::sigaction(kCleanupSignals[i], nullptr, &current) == 0 && (current.sa_flags & SA_SIGINFO) == 0 &&
          current.sa_handler == removeTempFilesOnSignal)
        ::sigaction(kCleanupSignals[i], &gPrevious[i], nullptr);
      gInstalled[i] = false;
    }
  }
}

void removeStaleTempFiles(const std::filesystem::path& target) {
  const std::filesystem::path folder = target.parent_path().empty() ? std::filesystem::path(".") : target.parent_path();
  const std::string prefix = "." + target.filename().string() + ".tmp";
  DIR* dir = ::opendir(folder.c_str());
  if (!dir) return;
  const pid_t self = ::getpid();
  while (const dirent* entry = ::readdir(dir)) {
    const std::string_view name(entry->d_name);
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    // <pid>.<n>: decimal digits, a dot, decimal digits, nothing else.
    size_t i = prefix.size();
    long long pid = 0;
    size_t digits = 0;
    for (; i < name.size() && name[i] >= '0' && name[i] <= '9' && digits < 10; ++i, ++digits)
      pid = pid * 10 + (name[i] - '0');
    if (digits == 0 || i >= name.size() || name[i] != '.') continue;
    size_t counterDigits = 0;
    for (++i; i < name.size() && name[i] >= '0' && name[i] <= '9'; ++i) ++counterDigits;
    if (counterDigits == 0 || i != name.size()) continue;
    if (pid <= 0 || pid > std::numeric_limits<pid_t>::max() || pid_t(pid) == self) continue;
    if (!(::kill(pid_t(pid), 0) == -1 && errno == ESRCH)) continue;  // alive (or not ours to judge)
    struct stat st {};
    if (::fstatat(::dirfd(dir), entry->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;
    if (!S_ISREG(st.st_mode) || st.st_uid != ::geteuid()) continue;
    ::unlinkat(::dirfd(dir), entry->d_name, 0);
  }
  ::closedir(dir);
}

Status commitFile(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  if (std::optional<InputFileRecord> input = findInputFile(path)) {
    std::filesystem::remove(tmp, ec);
    const std::string what = input->role.empty() ? "read as '" + input->path + "'" : input->role;
    return makeError(ErrorCode::InvalidArgument,
                     fmt::format("{}: is an input of this command ({}); refused: an output never replaces an input "
                                 "(nothing was written)",
                                 path, what));
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    const std::string why = ec.message();
    std::filesystem::remove(tmp, ec);
    return makeError(ErrorCode::IoError, fmt::format("{}: cannot move the finished file into place ({})", path, why));
  }
  noteOutputFile(path);
  return {};
}

}  // namespace visbuf
