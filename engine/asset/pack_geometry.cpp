#include "visbuf/asset/pack_geometry.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cstring>
#include <mutex>

#include "visbuf/asset/pack_format.h"

namespace visbuf::pack {

namespace {

// meshoptimizer keeps the encoder versions in globals: set them once, before the first encode, so that encoders
// running on several threads (parallel bakes) never race on them.
void pinEncoderVersions() {
  static std::once_flag once;
  std::call_once(once, [] {
    meshopt_encodeVertexVersion(0);
    meshopt_encodeIndexVersion(1);
  });
}

std::string codecError(int rc) {
  switch (rc) {
    case -1: return "unsupported or damaged stream header (codec error -1)";
    case -2: return "the stream ends before its data does (truncated or too short; codec error -2)";
    case -3: return "the stream's size does not match the decoded count (codec error -3)";
    default: return "codec error " + std::to_string(rc);
  }
}

std::vector<uint32_t> decodeTriangles(const std::vector<uint8_t>& bytes, size_t count) {
  std::vector<uint32_t> out(count);
  if (meshopt_decodeIndexBuffer(out.data(), count, sizeof(uint32_t), bytes.data(), bytes.size()) != 0) out.clear();
  return out;
}

std::vector<uint8_t> encodeTriangles(const uint32_t* indices, size_t count) {
  pinEncoderVersions();
  const uint32_t maxIndex = count ? *std::max_element(indices, indices + count) : 0;
  std::vector<uint8_t> bytes(meshopt_encodeIndexBufferBound(count, size_t{maxIndex} + 1));
  bytes.resize(meshopt_encodeIndexBuffer(bytes.data(), bytes.size(), indices, count));
  return bytes;
}

}  // namespace

std::vector<uint8_t> encodeVertexStream(const void* records, size_t count, size_t stride) {
  pinEncoderVersions();
  std::vector<uint8_t> bytes(meshopt_encodeVertexBufferBound(count, stride));
  bytes.resize(meshopt_encodeVertexBuffer(bytes.data(), bytes.size(), records, count, stride));
  return bytes;
}

EncodedIndices encodeIndexStream(const uint32_t* indices, size_t count) {
  EncodedIndices out;
  if (count % 3 == 0) {
    out.bytes = encodeTriangles(indices, count);
    const std::vector<uint32_t> back = decodeTriangles(out.bytes, count);
    if (back.size() == count && std::equal(back.begin(), back.end(), indices)) {
      out.codec = kIndexCodecTriangles;
      return out;
    }
  }
  pinEncoderVersions();
  const uint32_t maxIndex = count ? *std::max_element(indices, indices + count) : 0;
  out.bytes.assign(meshopt_encodeIndexSequenceBound(count, size_t{maxIndex} + 1), 0);
  out.bytes.resize(meshopt_encodeIndexSequence(out.bytes.data(), out.bytes.size(), indices, count));
  std::vector<uint32_t> back(count);
  if (meshopt_decodeIndexSequence(back.data(), count, sizeof(uint32_t), out.bytes.data(), out.bytes.size()) == 0 &&
      std::equal(back.begin(), back.end(), indices)) {
    out.codec = kIndexCodecSequence;
    return out;
  }
  out.bytes.resize(count * sizeof(uint32_t));
  if (count) std::memcpy(out.bytes.data(), indices, out.bytes.size());
  out.codec = kIndexCodecRaw;
  return out;
}

// Whether every triangle of `b` is a rotation of the same triangle of `a` (same vertices, same winding).
bool sameTrianglesRotated(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); t += 3) {
    bool same = false;
    for (size_t r = 0; r < 3 && !same; ++r)
      same = b[t] == a[t + r] && b[t + 1] == a[t + (r + 1) % 3] && b[t + 2] == a[t + (r + 2) % 3];
    if (!same) return false;
  }
  return true;
}

bool rotateTrianglesToCodecOrder(std::vector<uint32_t>& indices) {
  if (indices.empty() || indices.size() % 3 != 0) return false;
  std::vector<uint32_t> current = indices;
  for (int pass = 0; pass < 4; ++pass) {
    std::vector<uint32_t> next = decodeTriangles(encodeTriangles(current.data(), current.size()), current.size());
    // The codec's deltas wrap for very large index jumps: anything but a rotation leaves the mesh as it was.
    if (!sameTrianglesRotated(indices, next)) return false;
    if (next == current) {
      indices = std::move(current);
      return true;
    }
    current = std::move(next);
  }
  return false;
}

std::string decodeVertexStream(void* out, size_t count, size_t stride, const uint8_t* data, size_t size) {
  // The decoder asserts on these instead of failing: check them first.
  if (stride == 0 || stride > 256 || stride % 4 != 0) return "unsupported record size " + std::to_string(stride);
  const int rc = meshopt_decodeVertexBuffer(out, count, stride, data, size);
  return rc == 0 ? std::string() : codecError(rc);
}

std::string decodeIndexStream(uint32_t* out, size_t count, uint32_t codec, const uint8_t* data, size_t size) {
  int rc = 0;
  if (codec == kIndexCodecTriangles) {
    if (count % 3 != 0) return "the triangle codec needs a multiple of 3 indices, not " + std::to_string(count);
    rc = meshopt_decodeIndexBuffer(out, count, sizeof(uint32_t), data, size);
  } else if (codec == kIndexCodecSequence) {
    rc = meshopt_decodeIndexSequence(out, count, sizeof(uint32_t), data, size);
  } else if (codec == kIndexCodecRaw) {
    if (size != count * sizeof(uint32_t))
      return "a raw index stream of " + std::to_string(size) + " bytes does not hold " + std::to_string(count) +
             " indices";
    if (count) std::memcpy(out, data, size);
  } else {
    return "unknown index codec " + std::to_string(codec);
  }
  return rc == 0 ? std::string() : codecError(rc);
}

}  // namespace visbuf::pack
