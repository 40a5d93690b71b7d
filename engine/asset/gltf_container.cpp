// The glTF/GLB container loader: file reading, GLB checking and re-packing, and the tinygltf parse.
// This is the one translation unit that compiles tinygltf's implementation (see gltf_detail.h).
#define TINYGLTF_IMPLEMENTATION
#include "visbuf/asset/gltf_detail.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

#include "visbuf/asset/gltf_extensions.h"
#include "visbuf/asset/gltf_import.h"
#include "visbuf/asset/gltf_validate.h"
#include "visbuf/asset/pack_format.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"

namespace visbuf::gltf_detail {

Status MemoryBudget::charge(uint64_t bytes, const std::string& what) {
  if (bytes > limit_ - used_) {
    return makeError(ErrorCode::CapacityExceeded,
                     what + ": needs " + str(bytes) + " more bytes, past the import memory budget of " + str(limit_) +
                         " bytes (" + str(used_) +
                         " already used; raise it with --max-import-memory, GltfImportOptions::maxMemoryBytes)");
  }
  used_ += bytes;
  return {};
}

namespace {

// ---------------------------------------------------------------------------------------------------------
// File loading

// A rough bound of a parsed JSON document's size per byte of text (nlohmann's values are 16 bytes, plus
// their vectors and maps), for the memory budget.
constexpr uint64_t kJsonDomBytesPerTextByte = 8;

// tinygltf's memory API takes an unsigned int size, and GLB cannot describe 4 GiB or more.
constexpr uint64_t kMaxGltfFileBytes = (uint64_t{1} << 32) - 65;

// The input itself: a regular file only, opened without blocking (a FIFO or device never hangs the import),
// within the budget.
Result<std::vector<uint8_t>> readFile(const std::string& path, MemoryBudget* budget) {
  uint64_t size = 0;
  const FileKind kind = probeFile(path, &size);
  if (kind == FileKind::Regular) {
    if (size > kMaxGltfFileBytes)
      return makeError(ErrorCode::Unsupported, path + ": files of 4 GiB or more are not supported");
    if (Status s = budget->charge(size, path + ": the file"); !s) return s.error();
  }
  FileReadOptions options;
  options.maxBytes = std::min(kMaxGltfFileBytes, size);  // a file that grows meanwhile is refused
  return readRegularFile(path, options);
}

uint32_t readU32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

constexpr uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"

// Inputs that are not glTF, recognised by their first bytes so that every entry point (bake, render --scene,
// render --mesh) says what the file is instead of showing a JSON parser's complaint. A glTF file is a GLB
// container (magic "glTF") or JSON text whose first non-blank character (after an optional UTF-8 BOM) is '{'.
// `glbName`: the file is named .glb, so text is reported as a bad GLB magic.
Status checkIsGltf(const std::vector<uint8_t>& bytes, const std::string& path, bool glbName) {
  auto startsWith = [&](std::string_view magic) {
    return bytes.size() >= magic.size() && std::memcmp(bytes.data(), magic.data(), magic.size()) == 0;
  };
  if (bytes.empty()) return malformed(path + ": not a glTF file (the file is empty)");
  if (startsWith("glTF")) return {};
  if (startsWith(std::string_view(pack::kMagic, 4)))
    return malformed(path + ": is a visbuf pack, not a glTF file; use render --scene (or render --mesh) to view it");
  struct Kind {
    std::string_view magic;
    const char* name;
  };
  static constexpr Kind kKnown[] = {
      {"\x89PNG\r\n\x1a\n", "a PNG image"},       {"\xff\xd8\xff", "a JPEG image"},
      {"\xabKTX 20\xbb", "a KTX2 texture"},         {"DDS ", "a DDS texture"},
      {"GIF8", "a GIF image"},                      {"BM", "a BMP image"},
      {"RIFF", "a RIFF file (WebP, WAV, ...)"},     {"PK\x03\x04", "a ZIP archive"},
      {"\x1f\x8b", "a gzip file"},                  {"%PDF", "a PDF document"},
      {"\x7f" "ELF", "an executable"},               {"ply\n", "a PLY mesh"},
      {"#?RADIANCE", "a Radiance HDR image"},       {"\x76\x2f\x31\x01", "an OpenEXR image"},
  };
  for (const Kind& k : kKnown)
    if (startsWith(k.magic)) return malformed(path + ": not a glTF file (it is " + k.name + ")");
  if (glbName) return malformed(path + ": not a GLB file (bad magic)");
  size_t i = startsWith("\xef\xbb\xbf") ? 3 : 0;
  while (i < bytes.size() && (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\n' || bytes[i] == '\r')) ++i;
  if (i < bytes.size() && bytes[i] == '{') return {};
  const char* what = i == bytes.size() ? "only white space" : bytes[i] == '[' ? "a JSON array, not an object"
                     : (bytes[i] == '#' || bytes[i] == 'v' || bytes[i] == 'o' || bytes[i] == 'm')
                         ? "text that looks like a Wavefront OBJ or another text format"
                         : "neither JSON nor GLB";
  return malformed(path + ": not a glTF file (" + std::string(what) +
                   "; a glTF file is a JSON object or a GLB container)");
}

struct GlbParts {
  std::string_view json;
  const uint8_t* bin = nullptr;  // null when there is no BIN chunk
  uint64_t binSize = 0;
};

// Splits a GLB container into its JSON and (first) BIN chunk, checking every length against the file.
Result<GlbParts> parseGlb(const std::vector<uint8_t>& bytes, const std::string& path) {
  if (bytes.size() < 20) return malformed(path + ": GLB file is truncated (" + str(bytes.size()) + " bytes)");
  const uint32_t version = readU32(bytes.data() + 4);
  if (version != 2) {
    return makeError(ErrorCode::Unsupported,
                     path + ": GLB version " + str(uint64_t{version}) + " is not supported (only glTF 2.0)");
  }
  const uint64_t length = readU32(bytes.data() + 8);
  if (length > bytes.size() || length < 20) {
    return malformed(path + ": GLB header length " + str(length) + " does not match the file size " +
                     str(bytes.size()));
  }
  GlbParts parts;
  bool haveJson = false;
  uint64_t offset = 12;
  while (offset + 8 <= length) {
    const uint64_t chunkLength = readU32(bytes.data() + offset);
    const uint32_t chunkType = readU32(bytes.data() + offset + 4);
    if (!rangeFits(offset + 8, chunkLength, length)) {
      return malformed(path + ": GLB chunk at byte " + str(offset) + " (length " + str(chunkLength) +
                       ") runs past the end of the file");
    }
    const uint8_t* data = bytes.data() + offset + 8;
    if (!haveJson) {
      if (chunkType != kGlbChunkJson) return malformed(path + ": first GLB chunk is not JSON");
      parts.json = std::string_view(reinterpret_cast<const char*>(data), chunkLength);
      haveJson = true;
    } else if (chunkType == kGlbChunkBin && parts.bin == nullptr) {
      parts.bin = data;
      parts.binSize = chunkLength;
    }  // other chunk types are reserved for extensions: ignore them
    offset += 8 + chunkLength;
  }
  if (!haveJson) return malformed(path + ": GLB file has no JSON chunk");
  return parts;
}

// Re-packs JSON + BIN into a canonical GLB (4-byte padded chunks, exact header length). We already validated
// the original container; handing tinygltf a canonical one keeps its own (laxer) GLB checks out of play.
std::vector<uint8_t> buildGlb(std::string_view json, const uint8_t* bin, uint64_t binSize) {
  auto pad4 = [](uint64_t n) { return (n + 3) & ~uint64_t{3}; };
  const uint64_t jsonPadded = pad4(json.size());
  const bool hasBin = bin != nullptr && binSize > 0;  // tinygltf rejects an empty BIN chunk; omit it
  const uint64_t binPadded = hasBin ? pad4(binSize) : 0;
  const uint64_t total = 12 + 8 + jsonPadded + (hasBin ? 8 + binPadded : 0);
  std::vector<uint8_t> out(total, 0);
  auto put32 = [&](uint64_t at, uint64_t v) {
    const uint32_t v32 = static_cast<uint32_t>(v);
    std::memcpy(out.data() + at, &v32, 4);
  };
  put32(0, kGlbMagic);
  put32(4, 2);
  put32(8, total);
  put32(12, jsonPadded);
  put32(16, kGlbChunkJson);
  std::memcpy(out.data() + 20, json.data(), json.size());
  std::fill(out.begin() + 20 + static_cast<std::ptrdiff_t>(json.size()),
            out.begin() + 20 + static_cast<std::ptrdiff_t>(jsonPadded), ' ');  // spec: pad JSON with spaces
  if (hasBin) {
    const uint64_t at = 20 + jsonPadded;
    put32(at, binPadded);
    put32(at + 4, kGlbChunkBin);
    std::memcpy(out.data() + at + 8, bin, binSize);
  }
  return out;
}

// A buffer marked as an EXT_meshopt_compression fallback (its data is never read).
bool isMeshoptFallback(const nlohmann::json& buffer) {
  if (!buffer.is_object()) return false;
  auto extensions = buffer.find("extensions");
  if (extensions == buffer.end() || !extensions->is_object()) return false;
  auto meshopt = extensions->find(kMeshoptExt);
  if (meshopt == extensions->end() || !meshopt->is_object()) return false;
  auto fallback = meshopt->find("fallback");
  return fallback != meshopt->end() && fallback->is_boolean() && fallback->get<bool>();
}

// EXT_meshopt_compression allows a "fallback" buffer with no uri (and, in a GLB, no data): every bufferView
// in it is meant to be decoded from a compressed buffer instead. tinygltf 2.7 insists on loading every buffer
// and fails on those, so we give such buffers a 4-byte placeholder data URI. The buffer keeps its extension
// object, which is how the importer later knows never to read it. Returns whether the document changed.
bool neutraliseMeshoptFallbackBuffers(nlohmann::json& doc) {
  auto buffers = doc.find("buffers");
  if (buffers == doc.end() || !buffers->is_array()) return false;
  bool changed = false;
  for (auto& buffer : *buffers) {
    if (!isMeshoptFallback(buffer)) continue;
    buffer["uri"] = "data:application/octet-stream;base64,AAAAAA==";
    buffer["byteLength"] = 4;
    changed = true;
  }
  return changed;
}

// A KHR_draco_mesh_compression primitive's indices accessor has no bufferView (its data is the Draco stream's
// faces), which tinygltf 2.7 refuses ("invalid bufferView"). Such primitives lose "indices" before tinygltf
// parses; the importer finds the accessor in refs->dracoIndices instead (validateGltfDocument has checked it is
// an accessor index). Returns whether the document changed.
bool detachDracoIndices(nlohmann::json& doc, LoadedReferences* refs) {
  auto meshes = doc.find("meshes");
  auto accessors = doc.find("accessors");
  if (meshes == doc.end() || !meshes->is_array() || accessors == doc.end() || !accessors->is_array()) return false;
  bool changed = false;
  for (size_t m = 0; m < meshes->size(); ++m) {
    auto prims = (*meshes)[m].is_object() ? (*meshes)[m].find("primitives") : (*meshes)[m].end();
    if (!(*meshes)[m].is_object() || prims == (*meshes)[m].end() || !prims->is_array()) continue;
    for (size_t p = 0; p < prims->size(); ++p) {
      nlohmann::json& prim = (*prims)[p];
      if (!prim.is_object() || !prim.contains("extensions") || !prim["extensions"].is_object() ||
          !prim["extensions"].contains(kDracoExt))
        continue;
      auto indices = prim.find("indices");
      if (indices == prim.end() || !indices->is_number_unsigned() || indices->get<uint64_t>() >= accessors->size())
        continue;
      const nlohmann::json& accessor = (*accessors)[indices->get<size_t>()];
      if (accessor.is_object() && accessor.contains("bufferView")) continue;  // tinygltf accepts it as it is
      refs->dracoIndices[{static_cast<int>(m), static_cast<int>(p)}] = indices->get<int>();
      prim.erase(indices);
      changed = true;
    }
  }
  return changed;
}

// tinygltf converts the JSON DOM recursively, so absurd nesting (e.g. 200k nested arrays in "extras") would
// overflow the stack before any of our checks run. Real glTF nests about ten levels; refuse anything deeper
// than this before parsing. (Brackets inside strings do not count.)
constexpr int kMaxJsonDepth = 512;

bool jsonDepthWithin(std::string_view text, int limit) {
  int depth = 0;
  bool inString = false;
  bool escaped = false;
  for (const char c : text) {
    if (inString) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        inString = false;
      }
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > limit) return false;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return true;
}

// Image "loader" that decodes nothing (texture_bake.cpp decodes with OpenImageIO). tinygltf calls it with the
// base64-decoded bytes of a data: URI image, which are kept (nothing else holds them), and with the bytes of a
// bufferView image *before* checking the view against its buffer, which are left alone: collectImages reads
// those through a range-checked view.
bool keepDataUriImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  if (image->bufferView < 0 && bytes != nullptr && size > 0) {
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
  }
  return true;
}

void appendLines(const std::string& text, const std::string& prefix, std::vector<std::string>* out) {
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    if (end > start) out->push_back(prefix + text.substr(start, end - start));
    start = end + 1;
  }
}

// asset.version must be 2.x and asset.minVersion, when given, 2.0 ("2", "2.0", "2.1", ...).
bool isVersion2(const std::string& v, bool exactMinor0) {
  if (v == "2") return true;
  if (v.size() < 3 || v[0] != '2' || v[1] != '.') return false;
  for (size_t i = 2; i < v.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(v[i]))) return false;
  return !exactMinor0 || v.find_first_not_of('0', 2) == std::string::npos;
}

// The external files tinygltf may read: the path tinygltf will ask for (its JoinPath(baseDir, urldecode(uri)))
// -> the file the URI rule resolved. Nothing else can be opened through the callbacks below.
struct FsGate {
  std::map<std::string, std::string> approved;
  uint64_t maxBytes = 0;
};

bool gateFileExists(const std::string& path, void* user) {
  return static_cast<const FsGate*>(user)->approved.count(path) > 0;
}
std::string gateExpandFilePath(const std::string& path, void*) { return path; }
bool gateReadWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const FsGate& gate = *static_cast<const FsGate*>(user);
  auto it = gate.approved.find(path);
  if (it == gate.approved.end()) {
    if (err) *err += "not a file this import may read";
    return false;
  }
  FileReadOptions options;
  options.maxBytes = gate.maxBytes;
  options.noFollow = true;  // the resolved path is link-free
  Result<std::vector<uint8_t>> bytes = readRegularFile(it->second, options);
  if (!bytes) {
    if (err) *err += bytes.error().message;
    return false;
  }
  *out = std::move(bytes.value());
  return true;
}
bool gateWriteWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not allowed";
  return false;
}

// Before tinygltf sees the JSON: the version, the URI rule for every external buffer and image, and the
// buffers' sizes against the budget. A JSON text that does not parse is left to tinygltf to report.
Status preflight(const nlohmann::json& doc, const std::string& path, const std::string& baseDir,
                 const UriResolver& resolver, MemoryBudget* budget, FsGate* gate, LoadedReferences* refs) {
  if (doc.is_discarded() || !doc.is_object()) return {};
  if (auto asset = doc.find("asset"); asset != doc.end() && asset->is_object()) {
    auto version = asset->find("version");
    if (version != asset->end() && version->is_string() && !isVersion2(version->get<std::string>(), false)) {
      return makeError(ErrorCode::Unsupported, path + ": asset.version '" +
                                                   quoteForMessage(version->get<std::string>()) +
                                                   "' is not supported (only glTF 2.x)");
    }
    auto minVersion = asset->find("minVersion");
    if (minVersion != asset->end() && minVersion->is_string() &&
        !isVersion2(minVersion->get<std::string>(), true)) {
      return makeError(ErrorCode::Unsupported, path + ": asset.minVersion '" +
                                                   quoteForMessage(minVersion->get<std::string>()) +
                                                   "' is not supported (only glTF 2.0)");
    }
  }
  // Every index, count, offset, enum and number, before tinygltf narrows or drops it (gltf_validate.h).
  if (Status s = validateGltfDocument(doc, path); !s) return s;
  if (auto buffers = doc.find("buffers"); buffers != doc.end() && buffers->is_array()) {
    for (size_t i = 0; i < buffers->size(); ++i) {
      const nlohmann::json& buffer = (*buffers)[i];
      if (!buffer.is_object() || isMeshoptFallback(buffer)) continue;  // fallbacks are never read
      const std::string what = path + ": buffer " + str(uint64_t{i});
      auto uri = buffer.find("uri");
      if (uri == buffer.end() || !uri->is_string() || uri->get<std::string>().empty() ||
          isDataUri(uri->get<std::string>())) {
        // Embedded (GLB BIN chunk or data: URI): tinygltf allocates the declared length.
        auto length = buffer.find("byteLength");
        if (length != buffer.end() && length->is_number_unsigned()) {
          if (Status s = budget->charge(length->get<uint64_t>(), what); !s) return s;
        }
        continue;
      }
      const std::string& text = uri->get_ref<const std::string&>();
      Result<std::string> file = resolver.resolve(text, what);
      if (!file) return file.error();
      uint64_t size = 0;
      const FileKind kind = probeFile(*file, &size, /*noFollow=*/true);
      const std::string shown = what + ": uri '" + quoteForMessage(text) + "'";
      if (kind == FileKind::Missing) return makeError(ErrorCode::FileNotFound, shown + ": file not found");
      if (kind != FileKind::Regular) {
        return makeError(ErrorCode::InvalidArgument,
                         shown + ": not a regular file (" + fileKindName(kind) + "); only regular files are read");
      }
      if (Status s = budget->charge(size, shown); !s) return s;
      noteInputFile(*file, what);  // an input of the command: never replaced by one of its outputs
      const std::string key = tinygltf::JoinPath(baseDir, tinygltf::dlib::urldecode(text));
      auto [it, added] = gate->approved.emplace(key, *file);
      if (!added && it->second != *file) {
        return malformed(shown + ": ambiguous with another buffer's uri (they differ only in '+' / ' ')");
      }
    }
  }
  if (auto images = doc.find("images"); images != doc.end() && images->is_array()) {
    refs->imagePaths.assign(images->size(), std::string());
    for (size_t i = 0; i < images->size(); ++i) {
      const nlohmann::json& image = (*images)[i];
      if (!image.is_object()) continue;
      auto uri = image.find("uri");
      if (uri == image.end() || !uri->is_string() || uri->get<std::string>().empty() ||
          isDataUri(uri->get<std::string>()))
        continue;
      Result<std::string> file = resolver.resolve(uri->get_ref<const std::string&>(), path + ": image " + str(uint64_t{i}));
      if (!file) return file.error();
      noteInputFile(*file, path + ": image " + str(uint64_t{i}));  // an input, read or not (bake --no-textures)
      refs->imagePaths[i] = std::move(file.value());
    }
  }
  return {};
}

}  // namespace

Status loadModel(const std::string& path, const GltfImportOptions& options, MemoryBudget* budget,
                 tinygltf::Model* model, LoadedReferences* references, std::vector<std::string>* warnings) {
  auto bytes = readFile(path, budget);
  if (!bytes) return bytes.error();

  const bool isGlb = bytes->size() >= 4 && readU32(bytes->data()) == kGlbMagic;
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (Status s = checkIsGltf(*bytes, path, extension == ".glb"); !s) return s;

  Result<UriResolver> resolver = UriResolver::create(path, options.allowedUriRoots);
  if (!resolver) return resolver.error();
  const std::string baseDir = std::filesystem::path(path).parent_path().string();
  FsGate gate;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keepDataUriImage, nullptr);
  loader.SetFsCallbacks({&gateFileExists, &gateExpandFilePath, &gateReadWholeFile, &gateWriteWholeFile, &gate});

  // The JSON text (GLB: its JSON chunk), checked, resolved and patched before tinygltf parses it.
  std::optional<GlbParts> parts;
  std::string_view text;
  if (isGlb) {
    auto parsed = parseGlb(*bytes, path);
    if (!parsed) return parsed.error();
    parts = *parsed;
    // Some exporters pad the JSON chunk with NULs instead of spaces; the JSON parser would reject them.
    while (!parts->json.empty() && parts->json.back() == '\0') parts->json.remove_suffix(1);
    text = parts->json;
  } else {
    text = std::string_view(reinterpret_cast<const char*>(bytes->data()), bytes->size());
  }
  if (!jsonDepthWithin(text, kMaxJsonDepth)) {
    return malformed(path + ": JSON nesting deeper than " + str(kMaxJsonDepth) + " levels");
  }
  // The parsed document (ours, then tinygltf's) takes several times the text: charged as an estimate.
  if (Status s = budget->charge(uint64_t{kJsonDomBytesPerTextByte} * text.size(), path + ": the JSON document");
      !s)
    return s;
  nlohmann::json doc = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (Status s = preflight(doc, path, baseDir, *resolver, budget, &gate, references); !s) return s;
  // A required extension visbuf does not read is refused by name here, before the parser, which fails on some of
  // them with a message that does not say why; every used one it does not read fully is warned about once.
  if (Status s = auditGltfExtensions(doc, path, options.ignoreRequiredExtensions, warnings); !s) return s;
  gate.maxBytes = budget->limit();  // sizes were charged above; a file that grew since is refused by tinygltf
  std::optional<std::string> patched;
  if (doc.is_object()) {  // (a document that did not parse: tinygltf reports the syntax error itself)
    const bool meshopt = neutraliseMeshoptFallbackBuffers(doc);
    if (detachDracoIndices(doc, references) || meshopt)
      patched = doc.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  }
  nlohmann::json().swap(doc);  // freed before tinygltf builds its own
  const std::string_view json = patched ? std::string_view(*patched) : text;

  std::string err;
  std::string warn;
  bool ok = false;
  if (isGlb) {
    if (Status s = budget->charge(bytes->size(), path + ": the GLB container"); !s) return s;
    const std::vector<uint8_t> glb = buildGlb(json, parts->bin, parts->binSize);
    if (glb.size() > std::numeric_limits<unsigned int>::max()) {
      return makeError(ErrorCode::Unsupported, path + ": files of 4 GiB or more are not supported");
    }
    ok = loader.LoadBinaryFromMemory(model, &err, &warn, glb.data(), static_cast<unsigned int>(glb.size()),
                                     baseDir);
  } else {
    ok = loader.LoadASCIIFromString(model, &err, &warn, json.data(), static_cast<unsigned int>(json.size()),
                                    baseDir);
  }
  appendLines(warn, path + ": tinygltf: ", warnings);
  if (!ok) {
    if (err.empty()) err = "unknown error";
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    return malformed(path + ": glTF parse failed: " + err);
  }
  appendLines(err, path + ": tinygltf: ", warnings);  // non-fatal notes tinygltf reports through err
  references->imagePaths.resize(model->images.size());
  return {};
}

}  // namespace visbuf::gltf_detail
