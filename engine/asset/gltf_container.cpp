// The glTF/GLB container loader: file reading, GLB checking and re-packing, and the tinygltf parse.
// This is the one translation unit that compiles tinygltf's implementation (see gltf_detail.h).
#define TINYGLTF_IMPLEMENTATION
#include "asset/gltf_detail.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>

#include <nlohmann/json.hpp>

namespace visbuf::gltf_detail {
namespace {

// ---------------------------------------------------------------------------------------------------------
// File loading

Result<std::vector<uint8_t>> readFile(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    return makeError(ErrorCode::FileNotFound, path + ": file not found");
  }
  if (!std::filesystem::is_regular_file(status)) {
    return makeError(ErrorCode::FileNotFound, path + ": not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::IoError, path + ": cannot open for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) return makeError(ErrorCode::IoError, path + ": cannot determine file size");
  // tinygltf's memory API takes an unsigned int size, and GLB cannot describe 4 GiB or more.
  if (static_cast<uint64_t>(size) >= (uint64_t{1} << 32) - 64) {
    return makeError(ErrorCode::Unsupported, path + ": files of 4 GiB or more are not supported");
  }
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  in.seekg(0, std::ios::beg);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size)) {
    return makeError(ErrorCode::IoError, path + ": read failed");
  }
  return bytes;
}

uint32_t readU32(const uint8_t* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}

constexpr uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"

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

// EXT_meshopt_compression allows a "fallback" buffer with no uri (and, in a GLB, no data): every bufferView
// in it is meant to be decoded from a compressed buffer instead. tinygltf 2.7 insists on loading every buffer
// and fails on those, so we give such buffers a 4-byte placeholder data URI. The buffer keeps its extension
// object, which is how the importer later knows never to read it. Returns nullopt when nothing changes
// (including when the JSON does not parse: tinygltf then reports the syntax error itself).
std::optional<std::string> neutraliseMeshoptFallbackBuffers(std::string_view jsonText) {
  if (jsonText.find(kMeshoptExt) == std::string_view::npos) return std::nullopt;
  nlohmann::json doc = nlohmann::json::parse(jsonText.begin(), jsonText.end(), nullptr,
                                             /*allow_exceptions=*/false);
  if (doc.is_discarded() || !doc.is_object()) return std::nullopt;
  auto buffers = doc.find("buffers");
  if (buffers == doc.end() || !buffers->is_array()) return std::nullopt;
  bool changed = false;
  for (auto& buffer : *buffers) {
    if (!buffer.is_object()) continue;
    auto extensions = buffer.find("extensions");
    if (extensions == buffer.end() || !extensions->is_object()) continue;
    auto meshopt = extensions->find(kMeshoptExt);
    if (meshopt == extensions->end() || !meshopt->is_object()) continue;
    auto fallback = meshopt->find("fallback");
    if (fallback == meshopt->end() || !fallback->is_boolean() || !fallback->get<bool>()) continue;
    buffer["uri"] = "data:application/octet-stream;base64,AAAAAA==";
    buffer["byteLength"] = 4;
    changed = true;
  }
  if (!changed) return std::nullopt;
  return doc.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
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

// Reads and parses the file into a tinygltf::Model. Parse warnings go to `warnings`.
}  // namespace

Status loadModel(const std::string& path, tinygltf::Model* model, std::vector<std::string>* warnings) {
  auto bytes = readFile(path);
  if (!bytes) return bytes.error();

  const bool isGlb = bytes->size() >= 4 && readU32(bytes->data()) == kGlbMagic;
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (!isGlb && extension == ".glb") return malformed(path + ": not a GLB file (bad magic)");

  const std::string baseDir = std::filesystem::path(path).parent_path().string();
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&keepDataUriImage, nullptr);
  std::string err;
  std::string warn;
  bool ok = false;
  if (isGlb) {
    auto parts = parseGlb(*bytes, path);
    if (!parts) return parts.error();
    // Some exporters pad the JSON chunk with NULs instead of spaces; the JSON parser would reject them.
    while (!parts->json.empty() && parts->json.back() == '\0') parts->json.remove_suffix(1);
    if (!jsonDepthWithin(parts->json, kMaxJsonDepth)) {
      return malformed(path + ": JSON nesting deeper than " + str(kMaxJsonDepth) + " levels");
    }
    const std::optional<std::string> patched = neutraliseMeshoptFallbackBuffers(parts->json);
    const std::vector<uint8_t> glb =
        buildGlb(patched ? std::string_view(*patched) : parts->json, parts->bin, parts->binSize);
    if (glb.size() > std::numeric_limits<unsigned int>::max()) {
      return makeError(ErrorCode::Unsupported, path + ": files of 4 GiB or more are not supported");
    }
    ok = loader.LoadBinaryFromMemory(model, &err, &warn, glb.data(), static_cast<unsigned int>(glb.size()),
                                     baseDir);
  } else {
    const std::string_view text(reinterpret_cast<const char*>(bytes->data()), bytes->size());
    if (!jsonDepthWithin(text, kMaxJsonDepth)) {
      return malformed(path + ": JSON nesting deeper than " + str(kMaxJsonDepth) + " levels");
    }
    const std::optional<std::string> patched = neutraliseMeshoptFallbackBuffers(text);
    const std::string_view json = patched ? std::string_view(*patched) : text;
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
  return {};
}

}  // namespace visbuf::gltf_detail
