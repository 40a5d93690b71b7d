// The geometry codecs of a pack (pack_format.h, "meshEncoding"): meshoptimizer's vertex and index codecs with
// their format versions pinned (vertex 0, index 1), so the same mesh always encodes to the same bytes whatever
// meshoptimizer's default version is. Shared by the writer, the reader and the tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace visbuf::pack {

// `count` records of `stride` bytes (a multiple of 4, at most 256) through meshopt_encodeVertexBuffer.
std::vector<uint8_t> encodeVertexStream(const void* records, size_t count, size_t stride);

struct EncodedIndices {
  std::vector<uint8_t> bytes;
  uint32_t codec = 0;  // kIndexCodecTriangles, kIndexCodecSequence or kIndexCodecRaw
};

// Mesh-local indices (all LODs of one mesh), in the first of these whose decoded output equals `indices` exactly:
// the triangle codec (meshopt_encodeIndexBuffer; compresses best but may rotate the vertices of a triangle), the
// sequence codec (meshopt_encodeIndexSequence; its deltas wrap for jumps of 2^30 and more), raw uint32_t. So a pack
// always reproduces the scene's indices bit for bit.
EncodedIndices encodeIndexStream(const uint32_t* indices, size_t count);

// Rotates each triangle of a triangle list into the vertex order the triangle codec reproduces (a fixed point of
// encode + decode, found in at most a few passes), so that encodeIndexStream() can use the triangle codec. The
// triangles, their order and winding are unchanged; only which vertex comes first may change. Leaves `indices`
// unchanged (and returns false) when no fixed point is found, e.g. for degenerate triangles.
bool rotateTrianglesToCodecOrder(std::vector<uint32_t>& indices);

// Decoders: "" on success, else why the stream was refused (the codec's error). `count` records are written to
// `out`; the codecs are safe on hostile input (they never read or write outside the given ranges).
std::string decodeVertexStream(void* out, size_t count, size_t stride, const uint8_t* data, size_t size);
std::string decodeIndexStream(uint32_t* out, size_t count, uint32_t codec, const uint8_t* data, size_t size);

}  // namespace visbuf::pack
