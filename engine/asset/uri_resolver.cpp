// The URI rule for external glTF references (contract in uri_resolver.h, user-facing text in docs/security.md).
#include "visbuf/asset/uri_resolver.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <deque>
#include <filesystem>
#include <system_error>
#include <vector>

namespace visbuf {

namespace {

namespace fs = std::filesystem;

constexpr int kMaxSymlinks = 40;  // as Linux's own limit for one lookup

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Absolute, lexically normal, without a trailing '/' (except "/" itself).
std::string normalAbsolute(const fs::path& p) {
  std::string s = p.lexically_normal().string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

bool within(const std::string& path, const std::string& root) {
  if (root == "/") return !path.empty() && path[0] == '/';
  return path.size() >= root.size() && path.compare(0, root.size(), root) == 0 &&
         (path.size() == root.size() || path[root.size()] == '/');
}

// "a/b/c" -> {"a", "b", "c"}; empty and "." components dropped.
void splitInto(std::string_view path, std::deque<std::string>* out, bool front) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string_view::npos) end = path.size();
    std::string part(path.substr(start, end - start));
    if (!part.empty() && part != ".") parts.push_back(std::move(part));
    start = end + 1;
  }
  if (front) {
    out->insert(out->begin(), parts.begin(), parts.end());
  } else {
    out->insert(out->end(), parts.begin(), parts.end());
  }
}

std::string parentOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos || slash == 0) return "/";
  return path.substr(0, slash);
}

std::string join(const std::string& dir, const std::string& name) {
  return dir == "/" ? "/" + name : dir + "/" + name;
}

size_t depthOf(const std::string& path) {
  size_t depth = 0;
  for (size_t i = 0; i < path.size(); ++i)
    if (path[i] == '/' && i + 1 < path.size()) ++depth;
  return depth;
}

bool hasScheme(std::string_view uri) {
  if (uri.empty() || !std::isalpha(static_cast<unsigned char>(uri[0]))) return false;
  for (size_t i = 1; i < uri.size(); ++i) {
    const char c = uri[i];
    if (c == ':') return true;
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '-' && c != '.') return false;
  }
  return false;
}

}  // namespace

std::string percentDecodeUri(std::string_view uri) {
  std::string out;
  out.reserve(uri.size());
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && hexValue(uri[i + 1]) >= 0 && hexValue(uri[i + 2]) >= 0) {
      out += static_cast<char>(hexValue(uri[i + 1]) * 16 + hexValue(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

bool isDataUri(std::string_view uri) {
  if (uri.size() < 5) return false;
  static constexpr char kData[] = "data:";
  for (size_t i = 0; i < 5; ++i)
    if (std::tolower(static_cast<unsigned char>(uri[i])) != kData[i]) return false;
  return true;
}

std::string quoteForMessage(std::string_view text, size_t maxLength) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  auto escapeByte = [&](unsigned char c) {
    out += "\\x";
    out += kHex[c >> 4];
    out += kHex[c & 15];
  };
  size_t i = 0;
  while (i < text.size()) {
    if (out.size() >= maxLength) {
      out += "...";
      break;
    }
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\\' || c == '\'') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20 || c == 0x7f) {
      escapeByte(c);
    } else if (c < 0x80) {
      out += static_cast<char>(c);
    } else {
      // A well-formed UTF-8 sequence is kept unless it encodes a C1 control (U+0080..U+009F), which some
      // terminals obey like ESC; anything else is escaped byte by byte.
      size_t len = c >= 0xF0 && c <= 0xF4 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 && c <= 0xDF ? 2 : 0;
      if (c >= 0xF5) len = 0;
      bool ok = len > 0 && i + len <= text.size();
      for (size_t k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
      if (ok && len == 2 && c == 0xC2 && static_cast<unsigned char>(text[i + 1]) < 0xA0) ok = false;
      if (ok) {
        out.append(text.substr(i, len));
        i += len;
        continue;
      }
      escapeByte(c);
    }
    ++i;
  }
  return out;
}

Result<UriResolver> UriResolver::create(const std::string& assetPath, const std::vector<std::string>& extraRoots) {
  UriResolver r;
  std::error_code ec;
  fs::path folder = fs::path(assetPath).parent_path();
  if (folder.empty()) folder = ".";
  const fs::path absolute = fs::absolute(folder, ec);
  if (ec) return makeError(ErrorCode::IoError, assetPath + ": cannot determine the asset's folder: " + ec.message());
  const fs::path canonical = fs::weakly_canonical(absolute, ec);
  if (ec) return makeError(ErrorCode::IoError, assetPath + ": cannot resolve the asset's folder: " + ec.message());
  r.roots_.push_back({normalAbsolute(absolute), normalAbsolute(canonical)});
  for (const std::string& extra : extraRoots) {
    const fs::path abs = fs::absolute(fs::path(extra), ec);
    if (ec || !fs::is_directory(abs, ec)) {
      return makeError(ErrorCode::InvalidArgument,
                       "allowed uri root '" + quoteForMessage(extra) + "': not an existing folder");
    }
    const fs::path canon = fs::canonical(abs, ec);
    if (ec) {
      return makeError(ErrorCode::InvalidArgument,
                       "allowed uri root '" + quoteForMessage(extra) + "': cannot be resolved: " + ec.message());
    }
    r.roots_.push_back({normalAbsolute(abs), normalAbsolute(canon)});
  }
  return r;
}

bool UriResolver::insideRoot(const std::string& canonicalPath) const {
  for (const Root& root : roots_)
    if (within(canonicalPath, root.canonical)) return true;
  return false;
}

std::vector<std::string> UriResolver::roots() const {
  std::vector<std::string> out;
  for (const Root& root : roots_) out.push_back(root.canonical);
  return out;
}

Result<std::string> UriResolver::resolve(std::string_view uri, const std::string& what) const {
  const std::string shown = what + ": uri '" + quoteForMessage(uri) + "'";
  // The one message for every location outside: it must not depend on what is there.
  const Error outside = makeError(ErrorCode::MalformedInput,
                                  shown + " resolves outside the asset's folder and the allowed roots; refused "
                                          "(only files inside the asset's folder are read; see --allow-uri-root)");
  if (uri.empty()) return makeError(ErrorCode::MalformedInput, shown + " is empty");
  if (hasScheme(uri)) {
    return makeError(ErrorCode::MalformedInput,
                     shown + " has a URI scheme; only relative paths and data: URIs are allowed");
  }
  const std::string decoded = percentDecodeUri(uri);
  if (decoded.find('\0') != std::string::npos)
    return makeError(ErrorCode::MalformedInput, shown + " contains a NUL byte");

  // 2. Lexically: no file-system access for a path that is outside already.
  const fs::path decodedPath(decoded);
  const std::string candidate =
      normalAbsolute(decodedPath.is_absolute() ? decodedPath : fs::path(roots_.front().lexical) / decodedPath);
  const Root* base = nullptr;
  std::string rest;
  for (const Root& root : roots_) {
    for (const std::string* form : {&root.lexical, &root.canonical}) {
      if (within(candidate, *form)) {
        base = &root;
        rest = candidate.substr(std::min(candidate.size(), form->size()));
        break;
      }
    }
    if (base) break;
  }
  if (!base) return outside;

  // 3. Resolve links from the root, component by component. `current` is a real, link-free path while
  // `missingDepth` is 0; once a component is missing, the rest is appended lexically (nothing below a missing
  // component exists) until a ".." climbs back above it.
  std::string current = base->canonical;
  std::deque<std::string> pending;
  splitInto(rest, &pending, false);
  int links = 0;
  size_t missingDepth = 0;  // depth of the first missing component; 0: none
  while (!pending.empty()) {
    const std::string component = std::move(pending.front());
    pending.pop_front();
    if (component == "..") {
      current = parentOf(current);
      if (missingDepth != 0 && depthOf(current) < missingDepth) missingDepth = 0;
      continue;
    }
    const std::string next = join(current, component);
    if (missingDepth != 0) {
      current = next;
      continue;
    }
    struct stat st {};
    if (::lstat(next.c_str(), &st) != 0) {
      missingDepth = depthOf(next);
      current = next;
      continue;
    }
    if (S_ISLNK(st.st_mode)) {
      if (++links > kMaxSymlinks) return makeError(ErrorCode::MalformedInput, shown + ": too many symbolic links");
      std::string target(static_cast<size_t>(st.st_size > 0 ? st.st_size : 0) + 256, '\0');
      const ssize_t n = ::readlink(next.c_str(), target.data(), target.size());
      if (n < 0 || static_cast<size_t>(n) >= target.size()) {
        missingDepth = depthOf(next);  // vanished or changed under us: treat as missing
        current = next;
        continue;
      }
      target.resize(static_cast<size_t>(n));
      if (!target.empty() && target[0] == '/') current = "/";
      splitInto(target, &pending, true);
      continue;
    }
    current = next;
  }

  // 4. The link-free result must lie inside a root.
  if (!insideRoot(current)) return outside;
  return current;
}

}  // namespace visbuf
