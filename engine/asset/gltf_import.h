// glTF 2.0 importer: flattens the default scene of a .gltf / .glb file into ONE MeshSource.
//
// The renderer draws one mesh many times (e.g. the Kitten stress scene), so the importer bakes every node's
// world transform into the vertices and concatenates all primitives into a single indexed triangle list.
// Materials, textures, cameras, lights, skins and animations are ignored (meshes come out in rest pose, with
// the mesh's default morph weights, or the node's weights where a node overrides them).
//
// Supported:
//   - .gltf (external .bin files and data: URIs) and .glb, told apart by the "glTF" magic, then by name.
//   - Scene: `scene` if set, else scenes[0], else every root node when the file has no scenes. Node hierarchy
//     with matrix or TRS transforms (composed in double precision); one mesh instanced by many nodes.
//     A node whose world matrix has a negative determinant gets its triangle winding flipped, so front faces
//     stay counter-clockwise.
//   - Primitive modes TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN (converted to lists; strip/fan triangles
//     that repeat an index are dropped). POINTS and LINE* primitives are skipped with a warning.
//   - Indexed (u8/u16/u32) and non-indexed primitives.
//   - Accessors: byteOffset, byteStride (interleaved), normalized integers (KHR_mesh_quantization), sparse
//     accessors, accessors without a bufferView (zeros + sparse).
//   - Attributes: POSITION (required; primitives without it are skipped with a warning); NORMAL (transformed
//     by the inverse-transpose of the world matrix and renormalised); TEXCOORD_0; COLOR_0 (vec3/vec4 of
//     float, unorm8 or unorm16, packed to RGBA8 with R in the low byte, values stored as found, i.e. linear).
//     uvs / colors are filled with (0,0) / 0xFFFFFFFF for primitives lacking them when another primitive has
//     them, and left empty when no imported primitive has them.
//   - Morph targets: POSITION and NORMAL deltas weighted by node.weights or else mesh.weights.
//   - Missing normals: area-weighted smooth normals per primitive instance, computed after the transform
//     (options.generateNormalsIfMissing). When disabled, such vertices get (0,0,0) normals plus a warning.
//     Zero-length normals in the file are replaced the same way (with a warning).
//   - EXT_meshopt_compression (vertex codec v0, index buffer / index sequence codecs, OCTAHEDRAL, QUATERNION
//     and EXPONENTIAL filters), including fallback buffers without a uri.
//
// Errors (the message names the file and, where it applies, node / mesh / primitive / accessor):
//   - FileNotFound: `path` does not exist or is not a regular file.
//   - IoError: the file exists but could not be read.
//   - MalformedInput: tinygltf parse failure (its error text is included); GLB container damage; any
//     offset/count/stride that runs past its bufferView or buffer; index values >= vertex count; invalid
//     component types for an attribute; NaN/Inf in positions, normals, morph deltas/weights or node
//     transforms ("node 3 'Foo': non-finite transform"); node graph cycles or nodes with several parents;
//     JSON nested deeper than 512 levels; a scene that produces no triangles ("no triangle geometry").
//   - Unsupported: a required extension that changes geometry and is not handled (e.g.
//     KHR_draco_mesh_compression), an EXT_meshopt_compression view that cannot be decoded while the extension
//     is required, GLB versions other than 2, files of 4 GiB or more.
//   - CapacityExceeded: more than 2^32-1 vertices, or memory exhausted.
// Nothing in the file's contents can make the importer assert or crash.
//
// Not supported: KHR_draco_mesh_compression and EXT_mesh_gpu_instancing (Unsupported when required; when only
// used, the plain nodes are imported), TEXCOORD_1+ / COLOR_1+ / TANGENT (ignored), skinning and animation,
// KHR_texture_transform (quantized uvs that rely on it come out in their raw integer range).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/result.h"
#include "scene/mesh.h"

namespace visbuf {

struct GltfImportOptions {
  bool generateNormalsIfMissing = true;
};

struct GltfImportReport {
  std::vector<std::string> warnings;  // non-fatal issues (skipped primitives, replaced normals, ...)
  // Counted per primitive *instance*: a mesh of 2 primitives used by 3 nodes adds 6.
  uint32_t primitivesImported = 0;  // emitted at least one triangle
  uint32_t primitivesSkipped = 0;   // points/lines, no POSITION, or no triangles
};

// Imports the default scene of the glTF file at `path` as one triangle mesh (see the contract above).
// `report` may be null. MeshSource::name is the file name without its extension.
Result<MeshSource> importGltfMesh(const std::string& path, const GltfImportOptions& options = {},
                                  GltfImportReport* report = nullptr);

}  // namespace visbuf
