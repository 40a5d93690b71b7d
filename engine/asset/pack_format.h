// The visbuf pack (.vbp): a baked Scene (meshes with LOD chains, materials, objects, default camera) in one
// little-endian binary file that loads without any processing. docs/pack-format.md is the full description
// (policy, what readers reject); this header is the normative layout. Every record is plain data, copied with
// memcpy (never read in place through a cast), sizes pinned by static_assert.
//
// File layout (all offsets in bytes from the start of the file):
//
//   [0, 64)                  Header
//   [64, 64 + 64 * count)    SectionEntry[Header::sectionCount]   (the section table)
//   then the sections, each starting at a multiple of kAlignment (16), zero padding in between and after
//   the last one up to Header::fileSize, which is a multiple of 16.
//
// Integrity: Header::headerCrc is the CRC-32 of the header (with headerCrc itself set to 0) followed by the
// whole section table; SectionEntry::crc32 is the CRC-32 of the section's `storedSize` bytes as stored (for a
// zstd section the compressed bytes: checked before any decoder runs; each zstd frame's own content checksum then
// covers the decoded bytes). CRC-32 is the
// IEEE 802.3 / zlib / PNG one (reflected polynomial 0xEDB88320, initial value and final XOR 0xFFFFFFFF).
//
// Versioning: Header::version is kVersion. Any change to the layout or meaning of an existing record or
// section bumps it, and readers refuse every version other than their own (the user re-bakes). A writer may
// add sections that older readers of the same version can ignore; readers skip unknown section names (still
// range- and CRC-checked).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "visbuf/shared/types.h"

namespace visbuf::pack {

static_assert(std::endian::native == std::endian::little, "packs are little-endian; add byte swapping");

inline constexpr char kMagic[4] = {'V', 'B', 'P', 'K'};
// 2: full materials, textures, tangent / uv1 streams. 3: quantised vertices ("qvertices" + "quantization" instead
// of "vertices"; exactly one of the two vertex sections is present). 4: animated morph targets (the "morph*"
// sections of pack_animation_format.h): a mesh with targets stores its base shape, which a version-3 reader
// would draw without the node's default weights. 5: block-compressed texture classes (TextureClassRecord::format)
// and meshoptimizer-encoded geometry sections; the file is read in place from a memory mapping. 6: rigid node
// animation ("rigidObjects", pack_animation_format.h): an unskinned object that node animation moves is a plain
// object listed there (no longer a one-joint skin), which a version-5 reader would draw without its motion.
// 7: section encodings (SectionEntry grew to 64 bytes: storedSize, encoding): a section may be stored as zstd
// frames (ZstdSectionHeader below), which a version-6 reader would misread as raw records; and the material
// extensions (MaterialRecord: unlit, clearcoat factors and three clearcoat texture slots).
inline constexpr uint32_t kVersion = 7;
inline constexpr uint64_t kAlignment = 16;    // every section offset and the file size are multiples of this
inline constexpr uint32_t kMaxSections = 64;  // readers refuse longer section tables
inline constexpr size_t kSectionNameSize = 16;

struct Header {
  char magic[4];              // "VBPK"
  uint32_t version;           // kVersion
  uint32_t headerSize;        // sizeof(Header) = 64
  uint32_t sectionEntrySize;  // sizeof(SectionEntry) = 64
  uint32_t sectionCount;      // entries in the table at offset headerSize; 1..kMaxSections
  uint32_t flags;             // 0 (none defined)
  uint64_t fileSize;          // total file size in bytes, multiple of kAlignment
  uint32_t reserved[7];       // 0
  uint32_t headerCrc;         // CRC-32 of header (this field = 0) + section table
};
static_assert(sizeof(Header) == 64 && offsetof(Header, fileSize) == 24 && offsetof(Header, headerCrc) == 60);

// How a section's bytes are stored (SectionEntry::encoding). Every reader check below the section table sees the
// decoded bytes; the encoding is invisible above it.
inline constexpr uint32_t kSectionRaw = 0;   // storedSize == size: the bytes as they are
inline constexpr uint32_t kSectionZstd = 1;  // ZstdSectionHeader + frame sizes + zstd frames, decoding to `size` bytes

struct SectionEntry {
  char name[kSectionNameSize];  // ASCII, NUL-padded, at least one NUL (e.g. "indices")
  uint64_t offset;              // of the stored bytes, from the start of the file; multiple of kAlignment; after
                                // the table
  uint64_t size;                // decoded bytes; == count * elementSize
  uint64_t count;               // number of records
  uint32_t elementSize;         // bytes per record (1 for "strings")
  uint32_t crc32;               // CRC-32 of the section's `storedSize` bytes as stored in the file
  uint64_t storedSize;          // bytes in the file: == size for kSectionRaw, > 0 for kSectionZstd
  uint32_t encoding;            // kSectionRaw or kSectionZstd
  uint32_t reserved;            // 0
};
static_assert(sizeof(SectionEntry) == 64 && offsetof(SectionEntry, offset) == 16 &&
              offsetof(SectionEntry, crc32) == 44 && offsetof(SectionEntry, storedSize) == 48 &&
              offsetof(SectionEntry, encoding) == 56);

// The stored bytes of a kSectionZstd section: this header, then u32 frameBytes[frameCount] (each frame's stored
// length), then the frames back to back, exactly filling storedSize. Frame i is one zstd frame (RFC 8878; no
// skippable frame, no dictionary, content size and content checksum present) that decodes to the decoded bytes
// [i * chunkBytes, min((i + 1) * chunkBytes, size)): frames decode independently (in parallel, or only those a
// byte range needs). frameCount = ceil(size / chunkBytes); a section of size 0 is never compressed.
struct ZstdSectionHeader {
  uint32_t chunkBytes;  // decoded bytes per frame (the last one may hold fewer): a power of two in
                        // [kMinZstdChunkBytes, kMaxZstdChunkBytes]
  uint32_t frameCount;  // ceil(size / chunkBytes)
  uint64_t reserved;    // 0
};
static_assert(sizeof(ZstdSectionHeader) == 16);
inline constexpr uint32_t kMinZstdChunkBytes = uint32_t{1} << 12;
inline constexpr uint32_t kMaxZstdChunkBytes = uint32_t{1} << 24;

// A UTF-8 string in the "strings" section (not NUL-terminated). length 0: empty string.
struct StringRef {
  uint32_t offset;  // into the "strings" section
  uint32_t length;  // bytes
};
static_assert(sizeof(StringRef) == 8);

// Section "scene": exactly one record.
struct SceneRecord {
  StringRef name;
  double anchor[3];          // Scene::anchor (world units)
  double cameraPosition[3];  // Scene::defaultCamera
  double cameraTarget[3];
  double cameraUp[3];
  double cameraFovY;        // radians, in (0, pi)
  double cameraNear;        // > 0, world units
  float lightDirection[3];  // unit vector towards the light (world)
  uint32_t reserved;        // 0
};
static_assert(sizeof(SceneRecord) == 136 && offsetof(SceneRecord, lightDirection) == 120);

// Section "meshes": one record per Scene::meshes entry. Its vertices are records [firstVertex, firstVertex +
// vertexCount) and its indices (all LODs, mesh-local values below vertexCount) [firstIndex, firstIndex + indexCount)
// of the *decoded* vertex / index streams: the concatenation of every mesh's decoded data in mesh order, so
// firstVertex / firstIndex are the sums of the counts of the meshes before it. Its LODs are lods[firstLod, +
// lodCount). The encoded bytes are located by the mesh's MeshEncodingRecord.
struct MeshRecord {
  StringRef name;
  uint64_t firstVertex;   // sum of the vertexCounts of the meshes before this one
  uint64_t firstIndex;    // sum of their indexCounts
  uint32_t vertexCount;   // >= 1
  uint32_t indexCount;    // >= 3
  uint32_t firstLod;      // into "lods"
  uint32_t lodCount;      // 1..MAX_LODS; lods[firstLod] is the full mesh
  float boundsSphere[4];  // object space: centre xyz, radius w >= 0
};
static_assert(sizeof(MeshRecord) == 56 && offsetof(MeshRecord, boundsSphere) == 40);

// Section "lods": Lod records, ranges relative to their mesh's index range.
struct LodRecord {
  uint32_t firstIndex;  // relative to the mesh's firstIndex
  uint32_t indexCount;  // > 0, multiple of 3; firstIndex + indexCount <= mesh indexCount
  float error;          // object-space simplification error, finite, >= 0
  uint32_t reserved;    // 0
};
static_assert(sizeof(LodRecord) == 16);

// Geometry encoding. The sections "vertices", "qvertices", "indices", "tangents" and "uvs1" are byte streams
// (elementSize 1) holding one meshoptimizer-encoded stream per mesh, back to back in mesh order: vertex-like
// streams through meshopt_encodeVertexBuffer (format version 0), indices through meshopt_encodeIndexBuffer (format
// version 1) or, where that codec would not reproduce the mesh's exact index order, meshopt_encodeIndexSequence
// (or, where neither is exact, stored raw).
// Every mesh is encoded on its own (all its LODs in one index stream), so meshes decode independently.
//   decoded "vertices":  gpu::Vertex records as the GPU pool stores them (32 bytes, shaders/shared/types.h)
//   decoded "qvertices": QVertexRecord (20 bytes)
//   decoded "indices":   uint32_t, mesh-local
//   decoded "tangents":  float[4] per vertex; decoded "uvs1": float[2] per vertex (see MeshStreamsRecord)
static_assert(sizeof(gpu::Vertex) == 32);
inline constexpr uint32_t kIndexCodecTriangles = 0;  // meshopt_decodeIndexBuffer
inline constexpr uint32_t kIndexCodecSequence = 1;   // meshopt_decodeIndexSequence
inline constexpr uint32_t kIndexCodecRaw = 2;        // not encoded: indexCount uint32_t (see pack_geometry.h)

// Section "meshEncoding": one record per mesh, in mesh order: where its encoded streams are and what they decode
// to. Byte ranges lie inside their section; vertexCount / indexCount equal the mesh record's.
struct MeshEncodingRecord {
  uint64_t vertexByte;   // into "vertices" (or "qvertices"): the first byte of the mesh's encoded vertices
  uint64_t vertexBytes;  // their length
  uint64_t indexByte;    // into "indices"
  uint64_t indexBytes;
  uint32_t vertexCount;  // vertices the stream decodes to
  uint32_t indexCount;   // indices the stream decodes to (a multiple of 3 with kIndexCodecTriangles)
  uint32_t indexCodec;   // kIndexCodecTriangles, kIndexCodecSequence or kIndexCodecRaw
  uint32_t reserved;     // 0
};
static_assert(sizeof(MeshEncodingRecord) == 48 && offsetof(MeshEncodingRecord, vertexCount) == 32);

// Section "qvertices" (a quantised pack, `visbuf bake --quantize`; replaces "vertices"): decodes to one record per
// vertex, the mesh's record in "quantization" maps the integers back. A component q of a unorm16 field decodes as
// dequantizeUnorm16(offset, scale, q) = offset + scale * (q / 65535), evaluated in float exactly as written
// (the writer picks the q whose decoded value is nearest: error <= scale / 65535 / 2 + float rounding).
struct QVertexRecord {
  uint16_t position[3];  // unorm16 over the mesh's AABB: QuantizationRecord::positionOffset/Scale
  uint16_t reserved;     // 0
  uint32_t normal;       // gpu::Vertex::normal, unchanged (octahedral, 2 x snorm16)
  uint16_t uv[2];        // unorm16 over the mesh's uv range: QuantizationRecord::uvOffset/Scale
  uint32_t color;        // gpu::Vertex::color, unchanged (RGBA8)
};
static_assert(sizeof(QVertexRecord) == 20 && offsetof(QVertexRecord, normal) == 8 &&
              offsetof(QVertexRecord, uv) == 12 && offsetof(QVertexRecord, color) == 16);

// Section "quantization" (with "qvertices" only): one record per mesh, in mesh order. All finite, scales >= 0.
struct QuantizationRecord {
  float positionOffset[3];  // the AABB's minimum corner (mesh units)
  float positionScale[3];   // its extent: maximum - minimum (0 on a flat axis)
  float uvOffset[2];        // the uv range's minimum
  float uvScale[2];         // its extent
};
static_assert(sizeof(QuantizationRecord) == 40 && offsetof(QuantizationRecord, uvOffset) == 24);

inline float dequantizeUnorm16(float offset, float scale, uint16_t q) {
  return offset + scale * (static_cast<float>(q) / 65535.0f);
}

// The gpu::Vertex a quantised record stands for (pad 0).
inline gpu::Vertex dequantizeVertex(const QuantizationRecord& m, const QVertexRecord& q) {
  gpu::Vertex v{};
  v.px = dequantizeUnorm16(m.positionOffset[0], m.positionScale[0], q.position[0]);
  v.py = dequantizeUnorm16(m.positionOffset[1], m.positionScale[1], q.position[1]);
  v.pz = dequantizeUnorm16(m.positionOffset[2], m.positionScale[2], q.position[2]);
  v.normal = q.normal;
  v.u = dequantizeUnorm16(m.uvOffset[0], m.uvScale[0], q.uv[0]);
  v.v = dequantizeUnorm16(m.uvOffset[1], m.uvScale[1], q.uv[1]);
  v.color = q.color;
  v.pad = 0;
  return v;
}

inline constexpr uint32_t kMaterialDoubleSided = 1u;  // MaterialRecord::flags
inline constexpr uint32_t kMaterialUnlit = 2u;        // KHR_materials_unlit

// One texture reference of a material (TextureRef).
struct TextureSlotRecord {
  int32_t texture;      // into "textures" (the baked image), -1: none / not baked
  int32_t gltfTexture;  // source glTF texture index, -1: none
  int32_t gltfImage;    // source glTF image index, -1: none
  uint32_t texCoord;    // TEXCOORD_n: 0 or 1
  uint8_t wrapS;        // WrapMode: 0 repeat, 1 clamp to edge, 2 mirrored repeat
  uint8_t wrapT;
  uint8_t magFilter;    // TextureFilter: 0 nearest, 1 linear
  uint8_t minFilter;
  uint8_t mipFilter;    // MipFilter: 0 none, 1 nearest, 2 linear
  uint8_t reserved[3];  // 0
  float transform[6];   // uv' = M * (u, v, 1), M 3x2 column-major (KHR_texture_transform), finite
  StringRef uri;        // image URI relative to the source glTF, empty when embedded / none
};
static_assert(sizeof(TextureSlotRecord) == 56 && offsetof(TextureSlotRecord, transform) == 24 &&
              offsetof(TextureSlotRecord, uri) == 48);

// Section "materials": one record per Scene::materials entry. Factors are finite; colours linear.
struct MaterialRecord {
  StringRef name;
  float baseColor[4];          // linear RGBA
  float emissive[3];           // linear RGB
  float emissiveStrength;      // >= 0 (KHR_materials_emissive_strength)
  float metallic;
  float roughness;
  float normalScale;
  float occlusionStrength;
  uint32_t alphaMode;          // AlphaMode: 0 opaque, 1 mask, 2 blend
  float alphaCutoff;
  uint32_t flags;              // kMaterialDoubleSided | kMaterialUnlit
  uint32_t reserved;           // 0
  float clearcoat;             // [0,1] (KHR_materials_clearcoat; 0: no coat)
  float clearcoatRoughness;    // [0,1]
  float clearcoatNormalScale;  // finite
  uint32_t reserved2;          // 0
  // base colour, metallic-roughness, normal, occlusion, emissive, clearcoat, clearcoat roughness, clearcoat
  // normal (textureSlots())
  TextureSlotRecord textures[8];
};
static_assert(sizeof(MaterialRecord) == 536 && offsetof(MaterialRecord, alphaMode) == 56 &&
              offsetof(MaterialRecord, clearcoat) == 72 && offsetof(MaterialRecord, textures) == 88);

// Section "textures" (optional, with "textureClasses" and "texels"): one record per baked image.
struct TextureRecord {
  StringRef name;
  int32_t sourceImage;     // source glTF image index, -1: unknown
  uint32_t colorSpace;     // ColorSpace: 0 linear, 1 sRGB; equals its class's
  uint32_t sizeClass;      // into "textureClasses"
  uint32_t layer;          // < that class's layers; (sizeClass, layer) unique
  uint32_t originalWidth;  // of the source image, >= 1
  uint32_t originalHeight;
};
static_assert(sizeof(TextureRecord) == 32);

// Section "textureClasses": one 2D array texture each (TextureClass).
struct TextureClassRecord {
  uint32_t size;        // width = height, power of two in [1, 16384]
  uint32_t colorSpace;  // ColorSpace; 0 (linear) for formats bc4 / bc5
  uint32_t layers;      // 1..256
  uint32_t mipCount;    // log2(size) + 1
  uint32_t format;      // TextureFormat: 0 rgba8, 1 bc1, 2 bc3, 3 bc4, 4 bc5
  uint32_t reserved;    // 0
  uint64_t firstByte;   // into "texels", multiple of 16
  uint64_t byteCount;   // sum over mips m of layers * textureImageBytes(format, max(size >> m, 1)): rgba8
                        // side^2 * 4; BC ceil(side / 4)^2 blocks of 8 (bc1, bc4) or 16 (bc3, bc5) bytes
};
static_assert(sizeof(TextureClassRecord) == 40 && offsetof(TextureClassRecord, format) == 16 &&
              offsetof(TextureClassRecord, firstByte) == 24 && offsetof(TextureClassRecord, byteCount) == 32);

// Section "texels": bytes (elementSize 1); each class's texels (RGBA8 texels or BC blocks) at its firstByte,
// mip-major (all layers of mip 0, then of mip 1, ...), zero padding between classes.

inline constexpr uint64_t kNoStream = ~uint64_t{0};

// Section "meshStreams" (optional; absent: no mesh has extra streams): one record per mesh, in mesh order. Each
// stream present decodes (meshopt_decodeVertexBuffer) to the mesh's vertexCount records.
struct MeshStreamsRecord {
  uint64_t tangentByte;   // into "tangents": the mesh's encoded tangents, kNoStream: none
  uint64_t tangentBytes;  // their length (0 with kNoStream)
  uint64_t uv1Byte;       // into "uvs1", kNoStream: none
  uint64_t uv1Bytes;
};
static_assert(sizeof(MeshStreamsRecord) == 32);
// Decoded "tangents": float[4] per vertex (xyz unit, w = +-1, or all 0: none). Decoded "uvs1": float[2].

// Section "objects": one record per Scene::objects entry.
struct ObjectRecord {
  double transform[16];  // object -> world, column-major (glm::dmat4 memory order), finite, |det| > 0
  uint32_t mesh;         // < mesh count
  uint32_t material;     // < material count
  uint32_t flags;        // 0
  uint32_t reserved;     // 0
};
static_assert(sizeof(ObjectRecord) == 144 && offsetof(ObjectRecord, mesh) == 128);

// Section names; these nine (with "meshEncoding") are required, each at most once, except that a quantised pack
// has "qvertices" and "quantization" instead of "vertices" (exactly one of "vertices" / "qvertices").
inline constexpr const char* kSceneSection = "scene";
inline constexpr const char* kStringsSection = "strings";
inline constexpr const char* kMeshesSection = "meshes";
inline constexpr const char* kLodsSection = "lods";
inline constexpr const char* kVerticesSection = "vertices";
inline constexpr const char* kIndicesSection = "indices";
inline constexpr const char* kMaterialsSection = "materials";
inline constexpr const char* kObjectsSection = "objects";
// Optional sections (each at most once): textures (all three or none) and extra vertex streams.
inline constexpr const char* kTexturesSection = "textures";
inline constexpr const char* kTextureClassesSection = "textureClasses";
inline constexpr const char* kTexelsSection = "texels";
inline constexpr const char* kMeshStreamsSection = "meshStreams";
inline constexpr const char* kTangentsSection = "tangents";
inline constexpr const char* kUvs1Section = "uvs1";
inline constexpr const char* kQVerticesSection = "qvertices";
inline constexpr const char* kQuantizationSection = "quantization";
// Required: where each mesh's encoded geometry is.
inline constexpr const char* kMeshEncodingSection = "meshEncoding";
// Optional sections for skins, animation clips and skin vertices: pack_animation_format.h.

// CRC-32 (IEEE, as zlib's crc32()): crc32(b, crc32(a)) == crc32(a + b). Start with crc = 0.
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace visbuf::pack
