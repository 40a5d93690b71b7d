// The glTF extensions visbuf knows, what it does with each, and the audit every import runs before parsing.
//
// Rules (applied by auditGltfExtensions, before tinygltf parses anything that could fail on an extension):
//   - A file that lists an extension in extensionsRequired is imported only when visbuf reads that extension
//     (GltfExtensionSupport::Read); any other required extension, known or not, is refused by name
//     (ErrorCode::Unsupported) unless the caller lists it in GltfImportOptions::ignoreRequiredExtensions
//     (CLI: --ignore-required-extension NAME), which imports the file as if it were only used.
//   - An extension that is used (in extensionsUsed or as a key of any "extensions" object, whichever the file
//     says) and not fully read gives exactly one warning naming it and what is dropped; Partial ones say which
//     part is kept. Unknown extensions get one warning each too.
//   - Metadata extensions (nothing rendered depends on them) are listed as Read and give no warning.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "visbuf/core/result.h"

namespace visbuf {

enum class GltfExtensionSupport {
  Read,     // everything the extension says reaches the image (or it is metadata only)
  Partial,  // part of it is read; `dropped` says what is not (a warning when used; refused when required)
  Dropped,  // known but not read; the file renders as if it were absent (a warning; refused when required)
};

struct GltfExtension {
  std::string_view name;
  GltfExtensionSupport support;
  std::string_view effect;   // Read / Partial: what visbuf does with it, one line for docs and `visbuf extensions`
  std::string_view dropped;  // Partial / Dropped: what is lost, for the warning; empty for Read
};

// Every extension visbuf knows, sorted by name (docs/gltf.md lists the same rows; a unit test keeps them equal).
std::span<const GltfExtension> gltfExtensions();
// The row of `name`, or null for an extension visbuf does not know.
const GltfExtension* findGltfExtension(std::string_view name);

// The audit of a parsed glTF JSON document (`doc`: the whole top-level object): refuses required extensions
// visbuf cannot honour (see the rules above) and appends one warning per used extension that is not fully read
// to `warnings` (prefixed by `path`). `ignoreRequired` names required extensions to import anyway ("*": all).
Status auditGltfExtensions(const nlohmann::json& doc, const std::string& path,
                           const std::vector<std::string>& ignoreRequired, std::vector<std::string>* warnings);

}  // namespace visbuf
