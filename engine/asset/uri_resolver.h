// Where a glTF file's external references may point (docs/security.md).
//
// A glTF buffer or image names its file by a URI. Files come from the internet, so a URI is untrusted: it may
// climb out of the asset's folder ("../../etc/passwd", its percent-encoded form "..%2F..%2Fetc%2Fpasswd"), be
// absolute ("/home/me/.ssh/id_rsa"), or lead out through a symbolic link. The rule:
//
//   An external URI must resolve, after percent-decoding and canonicalisation (".", "..", symbolic links,
//   absolute paths), to a location inside the asset's own folder (the folder of the .gltf / .glb file) or
//   inside one of the extra allowed roots (GltfImportOptions::allowedUriRoots, `--allow-uri-root DIR`).
//   data: URIs are always fine; any other scheme ("file:", "http:") is refused.
//
// A URI that breaks the rule is refused with a message that names the URI and nothing else about the target:
// it is the same whether the target exists or not, is a file or a directory, so the error cannot be used to
// probe the file system. How it is resolved:
//   1. percent-decode (%XX; malformed escapes stay as they are); a NUL byte is refused;
//   2. join to the asset's folder (unless absolute) and normalise lexically; a path that is not then inside
//      an allowed root (as given, or as canonicalised) is refused without touching the file system;
//   3. resolve symbolic links component by component from that root (at most 40 links); a component that
//      does not exist ends the resolution, the rest is appended lexically;
//   4. the result, free of links, "." and "..", must lie inside a canonical allowed root.
// The resolved path is what gets opened (and only when it is a regular file: core/file_read.h).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "visbuf/core/result.h"

namespace visbuf {

// RFC 3986 percent-decoding: "%20" -> " " (a '%' not followed by two hex digits is kept as it is; '+' stays).
std::string percentDecodeUri(std::string_view uri);

// True for a data: URI (case-insensitive scheme).
bool isDataUri(std::string_view uri);

// The text with control characters, DEL, backslash and quote escaped (\n, \x1b, ...) and cut to
// `maxLength` bytes (then "..."): safe to print inside '...' in a message.
std::string quoteForMessage(std::string_view text, size_t maxLength = 200);

class UriResolver {
 public:
  // `assetPath`: the .gltf / .glb file; its folder is the first allowed root (the file itself need not
  // exist). `extraRoots`: more folders, each of which must exist (InvalidArgument otherwise).
  static Result<UriResolver> create(const std::string& assetPath, const std::vector<std::string>& extraRoots = {});

  // Resolves an external URI (not a data: URI) of the reference `what` (e.g. "Fox.gltf: buffer 0"; it
  // starts every message). On success, the canonical absolute path inside an allowed root; the file may not
  // exist. Errors (MalformedInput):
  //   "<what>: uri '<uri>' resolves outside the asset's folder and the allowed roots; refused"
  //   "<what>: uri '<uri>' has a URI scheme; only relative paths and data: URIs are allowed"
  //   "<what>: uri '<uri>' contains a NUL byte" / "is empty" / "... too many symbolic links"
  Result<std::string> resolve(std::string_view uri, const std::string& what) const;

  // True when `canonicalPath` (absolute, symlink-free) lies inside a canonical allowed root.
  bool insideRoot(const std::string& canonicalPath) const;

  // The canonical allowed roots, the asset's folder first.
  std::vector<std::string> roots() const;

 private:
  struct Root {
    std::string lexical;    // absolute, lexically normal, as given
    std::string canonical;  // symlinks resolved
  };
  std::vector<Root> roots_;
};

}  // namespace visbuf
