#include "cli_checks.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include <fmt/format.h>

#include "scene_options.h"
#include "visbuf/core/file_read.h"

namespace visbuf::tools {

namespace fs = std::filesystem;

// ---- printable ---------------------------------------------------------------------------------------------

std::string printable(std::string_view s, bool keepNewlines) {
  std::string out;
  out.reserve(s.size());
  auto escape = [&](size_t from, size_t count) {
    for (size_t k = 0; k < count; ++k) out += fmt::format("\\x{:02x}", static_cast<unsigned char>(s[from + k]));
  };
  size_t i = 0;
  while (i < s.size()) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      if ((c < 0x20 && !(keepNewlines && c == '\n')) || c == 0x7f)
        escape(i, 1);
      else
        out += char(c);
      ++i;
      continue;
    }
    // A UTF-8 sequence: its length from the lead byte, then continuation bytes, no overlong forms, no
    // surrogates, nothing above U+10FFFF. Anything else is a stray byte, escaped on its own.
    size_t len = 0;
    uint32_t cp = 0;
    if (c >= 0xc2 && c <= 0xdf) len = 2, cp = c & 0x1f;
    else if (c >= 0xe0 && c <= 0xef) len = 3, cp = c & 0x0f;
    else if (c >= 0xf0 && c <= 0xf4) len = 4, cp = c & 0x07;
    bool valid = len > 0 && i + len <= s.size();
    for (size_t k = 1; valid && k < len; ++k) {
      const unsigned char cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xc0) != 0x80) valid = false;
      cp = cp << 6 | (cc & 0x3f);
    }
    if (valid) {
      if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10ffff)) || (cp >= 0xd800 && cp <= 0xdfff))
        valid = false;
    }
    if (!valid) {
      escape(i, 1);
      ++i;
      continue;
    }
    const bool control = (cp >= 0x80 && cp <= 0x9f)                       // C1 (0x9b is CSI)
                         || cp == 0x2028 || cp == 0x2029                   // line / paragraph separator
                         || (cp >= 0x202a && cp <= 0x202e)                 // bidi embeddings and overrides
                         || (cp >= 0x2066 && cp <= 0x2069);                // bidi isolates
    if (control)
      escape(i, len);
    else
      out.append(s.data() + i, len);
    i += len;
  }
  return out;
}

// ---- validators --------------------------------------------------------------------------------------------

namespace {

std::string got(const std::string& text) { return fmt::format(" (got '{}')", printable(text)); }

std::string describeRange(double lo, double hi, bool loOpen, bool hiOpen) {
  const bool hasLo = std::isfinite(lo), hasHi = std::isfinite(hi);
  if (!hasLo && !hasHi) return "a finite number";
  if (hasLo && !hasHi) return fmt::format("a finite number {} {}", loOpen ? ">" : ">=", lo);
  if (!hasLo) return fmt::format("a finite number {} {}", hiOpen ? "<" : "<=", hi);
  return fmt::format("a finite number in {}{}, {}{}", loOpen ? "(" : "[", lo, hi, hiOpen ? ")" : "]");
}

// Parses a whole decimal integer (optional sign, digits); false on anything else or overflow.
bool parseInteger(const std::string& text, bool& negative, uint64_t& magnitude) {
  size_t i = 0;
  negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
  if (i == text.size()) return false;
  magnitude = 0;
  for (; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    const uint64_t d = uint64_t(text[i] - '0');
    if (magnitude > (UINT64_MAX - d) / 10) return false;
    magnitude = magnitude * 10 + d;
  }
  return true;
}

}  // namespace

CLI::Validator finiteNumber(double lo, double hi, bool loOpen, bool hiOpen) {
  const std::string range = describeRange(lo, hi, loOpen, hiOpen);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::string what = fmt::format("must be {}", range);
        if (text.empty()) return what + got(text);
        errno = 0;
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (end != text.c_str() + text.size() || !std::isfinite(v)) return what + got(text);
        if (loOpen ? !(v > lo) : !(v >= lo)) return what + got(text);
        if (hiOpen ? !(v < hi) : !(v <= hi)) return what + got(text);
        text = fmt::format("{}", v);  // exactly what was checked is what CLI11 converts
        return {};
      },
      range);
}

CLI::Validator integerIn(int64_t lo, int64_t hi) {
  const std::string range = fmt::format("an integer in {}..{}", lo, hi);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        bool negative = false;
        uint64_t m = 0;
        const std::string what = fmt::format("must be {}", range);
        if (!parseInteger(text, negative, m)) return what + got(text);
        if (m > uint64_t(INT64_MAX) + (negative ? 1 : 0)) return what + got(text);
        const int64_t v = negative ? int64_t(0 - m) : int64_t(m);
        if (v < lo || v > hi) return what + got(text);
        text = std::to_string(v);  // decimal, no leading zeros (CLI11's strtoll would read "010" as octal)
        return {};
      },
      range);
}

CLI::Validator unsignedIn(uint64_t lo, uint64_t hi) {
  const std::string range = fmt::format("an integer in {}..{}", lo, hi);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        bool negative = false;
        uint64_t m = 0;
        const std::string what = fmt::format("must be {}", range);
        if (!parseInteger(text, negative, m) || (negative && m != 0)) return what + got(text);
        if (m < lo || m > hi) return what + got(text);
        text = std::to_string(m);
        return {};
      },
      range);
}

CLI::Validator imageSize() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (Result<std::pair<uint32_t, uint32_t>> s = parseSize(text); !s)
          return fmt::format("expected WxH, each 1..16384{}", got(text));
        return {};
      },
      "WxH");
}

CLI::Validator powerOfTwo(uint32_t max) {
  const std::string range = fmt::format("a power of two in 1..{}", max);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        bool negative = false;
        uint64_t m = 0;
        if (!parseInteger(text, negative, m) || negative || m < 1 || m > max || (m & (m - 1)) != 0)
          return fmt::format("must be {}{}", range, got(text));
        text = std::to_string(m);
        return {};
      },
      range);
}

CLI::Validator nonEmptyPath() {
  return CLI::Validator([](std::string& text) -> std::string { return text.empty() ? "empty path" : ""; }, "PATH");
}

// ---- paths -------------------------------------------------------------------------------------------------

namespace {

std::string quoted(const std::string& path) { return "'" + printable(path) + "'"; }

// The folder a file of `path` goes into ("." for a bare name).
fs::path folderOf(const fs::path& p) {
  fs::path parent = p.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

Status checkWritableFolder(const std::string& option, const std::string& path, const fs::path& folder,
                           const char* role) {
  struct stat st {};
  if (::stat(folder.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT)
      return makeError(ErrorCode::IoError, fmt::format("{} {}: the folder {} does not exist", option, quoted(path),
                                                       quoted(folder.string())));
    return makeError(ErrorCode::IoError, fmt::format("{} {}: cannot use the folder {}: {}", option, quoted(path),
                                                     quoted(folder.string()), std::strerror(err)));
  }
  if (!S_ISDIR(st.st_mode))
    return makeError(ErrorCode::IoError,
                     fmt::format("{} {}: {} is not a folder", option, quoted(path), quoted(folder.string())));
  if (::faccessat(AT_FDCWD, folder.c_str(), W_OK | X_OK, AT_EACCESS) != 0) {
    const int err = errno;
    return makeError(ErrorCode::IoError, fmt::format("{} {}: cannot write into {} {}: {}", option, quoted(path), role,
                                                     quoted(folder.string()), std::strerror(err)));
  }
  return {};
}

}  // namespace

Status checkOutputFile(const std::string& option, const std::string& path) {
  if (path.empty()) return makeError(ErrorCode::InvalidArgument, fmt::format("{}: empty path", option));
  const fs::path p(path);
  if (!p.has_filename() || p.filename() == "." || p.filename() == "..")
    return makeError(ErrorCode::IoError, fmt::format("{} {}: names a folder, not a file", option, quoted(path)));
  struct stat st {};
  if (::stat(p.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode))
      return makeError(ErrorCode::IoError, fmt::format("{} {}: is a folder, not a file", option, quoted(path)));
    if (!S_ISREG(st.st_mode))
      return makeError(ErrorCode::IoError,
                       fmt::format("{} {}: is not a regular file (a FIFO, socket or device); the output is written "
                                   "to a temporary file and renamed over it",
                                   option, quoted(path)));
  }
  return checkWritableFolder(option, path, folderOf(p), "its folder");
}

Status checkOutputFolder(const std::string& option, const std::string& path) {
  if (path.empty()) return makeError(ErrorCode::InvalidArgument, fmt::format("{}: empty path", option));
  fs::path p(path);
  struct stat st {};
  if (::stat(p.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode))
      return makeError(ErrorCode::IoError, fmt::format("{} {}: is not a folder", option, quoted(path)));
    return checkWritableFolder(option, path, p, "the folder");
  }
  // Missing: it is created, in its nearest existing ancestor.
  fs::path ancestor = p.lexically_normal();
  while (true) {
    fs::path up = ancestor.parent_path();
    if (up.empty() || up == ancestor) {
      ancestor = p.is_absolute() ? up : fs::path(".");
      break;
    }
    ancestor = up;
    if (::stat(ancestor.c_str(), &st) == 0) break;
  }
  return checkWritableFolder(option, path, ancestor, "the folder it would be created in");
}

namespace {
// The same file: equal once resolved (the folders' links followed; the file need not exist), or the same existing
// file (hard link, symbolic link).
bool sameFile(const std::string& a, const std::string& b) {
  std::error_code ec1, ec2;  // absolute first: weakly_canonical leaves a relative path without existing prefix as is
  const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec1), ec1),
                 cb = fs::weakly_canonical(fs::absolute(b, ec2), ec2);
  if (!ec1 && !ec2 && ca == cb) return true;
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
         sa.st_ino == sb.st_ino;
}
}  // namespace

Status checkOutputs(const std::vector<OutputFile>& outputs) {
  for (size_t i = 0; i < outputs.size(); ++i) {
    const OutputFile& o = outputs[i];
    if (!o.inFolder)
      if (Status s = checkOutputFile(o.option, o.path); !s) return s;
    if (std::optional<InputFileRecord> input = findInputFile(o.path)) {
      const std::string what = input->role.empty() ? "read as " + tools::quoted(input->path) : printable(input->role);
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("{} {}: is an input of this command ({}); refused: an output never replaces an "
                                   "input",
                                   o.option, tools::quoted(o.path), what));
    }
    for (size_t j = 0; j < i; ++j) {
      if (sameFile(outputs[j].path, o.path))
        return makeError(ErrorCode::InvalidArgument,
                         fmt::format("{} {}: is the same file as {} {}; each output needs its own file", o.option,
                                     tools::quoted(o.path), outputs[j].option, tools::quoted(outputs[j].path)));
    }
  }
  return {};
}

// ---- memory ------------------------------------------------------------------------------------------------

namespace {

// A "Key:   N kB" line of a /proc file, in bytes; 0 when absent.
uint64_t procKilobytes(const char* file, const char* key) {
  std::ifstream in(file);
  std::string line;
  const size_t keyLen = std::strlen(key);
  while (std::getline(in, line)) {
    if (line.compare(0, keyLen, key) == 0 && line.size() > keyLen && line[keyLen] == ':')
      return std::strtoull(line.c_str() + keyLen + 1, nullptr, 10) * 1024;
  }
  return 0;
}

// cgroup v2: memory.max less memory.current of this process's group; UINT64_MAX without a limit.
uint64_t cgroupAvailable() {
  std::ifstream self("/proc/self/cgroup");
  std::string line, group;
  while (std::getline(self, line))
    if (line.rfind("0::", 0) == 0) group = line.substr(3);
  if (group.empty()) return UINT64_MAX;
  const std::string dir = "/sys/fs/cgroup" + group;
  std::ifstream maxFile(dir + "/memory.max"), currentFile(dir + "/memory.current");
  std::string max, current;
  if (!(maxFile >> max) || max == "max") return UINT64_MAX;
  const uint64_t limit = std::strtoull(max.c_str(), nullptr, 10);
  const uint64_t used = (currentFile >> current) ? std::strtoull(current.c_str(), nullptr, 10) : 0;
  return limit > used ? limit - used : 0;
}

}  // namespace

uint64_t availableHostMemory(std::string* source) {
  std::string from = "MemAvailable";
  uint64_t bytes = procKilobytes("/proc/meminfo", "MemAvailable");
  if (bytes == 0) {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    if (pages > 0 && pageSize > 0) bytes = uint64_t(pages) * uint64_t(pageSize);
    from = "physical memory";
  }
  if (bytes == 0) bytes = UINT64_MAX, from = "unknown";
  auto cap = [&](uint64_t limit, const char* what) {
    if (limit < bytes) bytes = limit, from = what;
  };
  cap(cgroupAvailable(), "the cgroup's memory.max");
  rlimit r{};
  if (::getrlimit(RLIMIT_AS, &r) == 0 && r.rlim_cur != RLIM_INFINITY) {
    const uint64_t used = procKilobytes("/proc/self/status", "VmSize");
    cap(r.rlim_cur > used ? r.rlim_cur - used : 0, "RLIMIT_AS (ulimit -v) less the address space in use");
  }
  if (::getrlimit(RLIMIT_DATA, &r) == 0 && r.rlim_cur != RLIM_INFINITY) {
    const uint64_t used = procKilobytes("/proc/self/status", "VmData");
    cap(r.rlim_cur > used ? r.rlim_cur - used : 0, "RLIMIT_DATA (ulimit -d) less the data in use");
  }
  if (source) *source = from;
  return bytes;
}

std::string formatBytes(uint64_t bytes) {
  if (bytes >= (1ull << 30)) return fmt::format("{:.1f} GiB", double(bytes) / double(1ull << 30));
  if (bytes >= (1ull << 20)) return fmt::format("{:.1f} MiB", double(bytes) / double(1ull << 20));
  return fmt::format("{} bytes", bytes);
}

}  // namespace visbuf::tools
