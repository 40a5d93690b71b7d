// glTF 2.0 importer. importGltfMesh() flattens the default scene of a .gltf / .glb file into ONE MeshSource;
// importGltfScene() (declared at the end) keeps the node hierarchy as instances of per-material meshes.
//
// importGltfMesh: the renderer draws one mesh many times (e.g. the Kitten stress scene), so it bakes every
// node's world transform into the vertices and concatenates all primitives into a single indexed triangle
// list.
// Materials, textures, cameras, lights, skins and animations are ignored (meshes come out in rest pose, with
// the mesh's default morph weights, or the node's weights where a node overrides them); importGltfScene reads
// materials, collects the images they use, and imports skins and animations (see below).
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
//     TEXCOORD_1 (as TEXCOORD_0, into uvs1). TANGENT (VEC4 of float or normalized byte/short): xyz transformed
//     by the world matrix's linear part and renormalised, w (handedness) multiplied by the sign of its
//     determinant; a primitive whose tangents are not all finite, of length 1 +- 0.1 with |w| = 1 +- 0.01 has
//     them dropped with a warning (they are then renormalised and w snapped to +-1).
//     uvs / colors / uvs1 / tangents are filled with (0,0) / 0xFFFFFFFF / (0,0) / (0,0,0,0) ("no tangent")
//     for primitives lacking them when another primitive has them, and left empty when no imported primitive
//     has them.
//   - Morph targets: POSITION and NORMAL deltas weighted by node.weights or else mesh.weights.
//   - Missing normals: area-weighted smooth normals per primitive instance, computed after the transform
//     (options.generateNormalsIfMissing). When disabled, such vertices get (0,0,0) normals plus a warning.
//     Zero-length normals in the file are replaced the same way (with a warning).
//   - EXT_meshopt_compression (vertex codec v0, index buffer / index sequence codecs, OCTAHEDRAL, QUATERNION
//     and EXPONENTIAL filters), including fallback buffers without a uri.
//   - KHR_draco_mesh_compression (also when required; libdraco, Draco bitstream 2.2 and older): TRIANGLES
//     primitives whose extension.attributes name any of the primitive's attributes (POSITION, NORMAL, TANGENT,
//     TEXCOORD_n, COLOR_n, JOINTS_n, WEIGHTS_n, ...) by Draco unique id; the decoded points fill those accessors
//     (dequantised by the decoder, converted to each accessor's declared component type) and the faces fill
//     the indices accessor, which then go through the same checks and budgets as any accessor. Attributes
//     outside the stream and morph targets are read as usual, in the decoded point order. The stream is
//     untrusted: its counts must be the accessors' (points == each attribute's count, faces x 3 == the indices
//     count), its ids must exist and not repeat, and the decoder's allocations are capped at a working set
//     charged to options.maxMemoryBytes (gltf_draco.cpp). A stream that cannot be decoded is MalformedInput
//     (Unsupported for a non-TRIANGLES primitive) unless the extension is only used and every accessor has a
//     bufferView: then the uncompressed data is used, with a warning.
//   - EXT_mesh_gpu_instancing (also when required): a node's TRANSLATION / ROTATION / SCALE accessors (any
//     subset; the extension's table: TRANSLATION and SCALE VEC3 of FLOAT, ROTATION VEC4 of FLOAT or normalized
//     BYTE / SHORT, decoded as glTF normalized integers) give one instance per element, at
//     world(node) x T_i x R_i x S_i (composed like a node's TRS, in double precision; rotations renormalised):
//     importGltfMesh bakes one copy of the mesh per instance, importGltfScene emits one ImportedInstance per
//     instance (all with `node` set to the instanced node; mirrored and zero-scale instances are handled one
//     by one, as separate nodes would be). The node's own light and children are not instanced.
//     MalformedInput, naming the node, the extension and the accessor: attributes that are not an object, an
//     accessor that does not exist or has another format, counts that differ between the attributes or are
//     outside [1, 2^24], NaN / Inf values, a zero-length rotation, a non-finite composed transform. A node
//     without a mesh, or with only custom ("_NAME") attributes, is imported once with a warning. A skinned or
//     animated node (its skin carries the node's transform, with no room for a per-instance one) is imported
//     once with a warning, or refused (Unsupported) when the file requires the extension.
//
// Untrusted files (docs/security.md): the file and its external buffers are read only when they are regular
// files (opened without blocking, so a FIFO or device fails at once); every external buffer / image uri must
// resolve inside the asset's folder or options.allowedUriRoots (uri_resolver.h), else MalformedInput with a
// message that names the uri and is the same whether or not the target exists; asset.version must be 2.x;
// decoded data is charged to options.maxMemoryBytes before it is allocated.
//
// Errors (the message names the file and, where it applies, node / mesh / primitive / accessor):
//   - FileNotFound: `path` (or an external buffer inside the allowed folders) does not exist.
//   - InvalidArgument: `path` or an external buffer is not a regular file (a FIFO, device or folder: "not a
//     regular file (a FIFO)"); an allowedUriRoots entry that is not an existing folder.
//   - IoError: the file exists but could not be read.
//   - MalformedInput: tinygltf parse failure (its error text is included); GLB container damage; any
//     offset/count/stride that runs past its bufferView or buffer; index values >= vertex count; invalid
//     component types for an attribute; NaN/Inf in positions, normals, morph deltas/weights or node
//     transforms ("node 3 'Foo': non-finite transform"); node graph cycles or nodes with several parents,
//     anywhere among the file's nodes (not only the scene's); coordinates beyond kMaxImportCoordinate;
//     an external uri outside the allowed folders or with a scheme other than data:;
//     JSON nested deeper than 512 levels; a scene that produces no triangles ("no triangle geometry").
//   - Unsupported: a required extension visbuf does not read (the table and the audit: gltf_extensions.h; used
//     ones not fully read are imported with one warning each), EXT_mesh_gpu_instancing on a skinned or animated
//     node while the file requires the extension, an EXT_meshopt_compression view that cannot be decoded while
//     the extension is required, GLB versions other than 2, asset.version other than 2.x (or minVersion other than 2.0),
//     files of 4 GiB or more.
//   - CapacityExceeded: more than 2^32-1 vertices, memory exhausted, or more than options.maxMemoryBytes.
// Nothing in the file's contents can make the importer assert or crash.
//
// Not supported (extensions: gltf_extensions.h, `visbuf extensions`): TEXCOORD_2+ / COLOR_1+ (ignored), morph
// target TANGENT deltas of baked targets (the base tangents are kept; animated targets keep them, see
// importGltfScene), JOINTS_2+ / WEIGHTS_2+ (more than 8
// influences per vertex: ignored with a warning, the first 8 renormalised), KHR_animation_pointer channels
// (ignored with a warning), KHR_texture_basisu images (KTX2 / Basis Universal: the texture's fallback `source`
// is used; without one the texture is dropped with a warning naming the extension and the texture).
// KHR_texture_transform is read into each TextureRef (scene import), never applied to the vertex uvs
// (quantized uvs that rely on it come out in their raw integer range).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "visbuf/core/result.h"
#include "visbuf/scene/mesh.h"
#include "visbuf/scene/scene.h"

namespace visbuf {

// Default import memory budget (GltfImportOptions::maxMemoryBytes): 4 GiB.
inline constexpr uint64_t kDefaultImportMemoryBytes = uint64_t{4} << 30;
// Default GltfImportOptions::maxInstances: 2^20 objects. A pack stores about 144 bytes per object and the scene
// build about 500 bytes per object at its peak, so this bounds a file of a few hundred bytes that asks for
// millions of EXT_mesh_gpu_instancing instances to about 150 MB of pack and well under 1 GB of memory.
inline constexpr uint64_t kDefaultMaxInstances = uint64_t{1} << 20;
// Largest |coordinate| of an imported vertex (object space for importGltfScene, world space for
// importGltfMesh, and every instance's world-space bounds): beyond it squared lengths overflow float and
// bounds, framing and culling stop working, so such files are refused (MalformedInput).
inline constexpr double kMaxImportCoordinate = 1e18;

struct GltfImportOptions {
  bool generateNormalsIfMissing = true;
  // Folders besides the asset's own that external buffer / image uris may resolve into (uri_resolver.h,
  // docs/security.md; `--allow-uri-root`). Each must exist.
  std::vector<std::string> allowedUriRoots;
  // What the import may hold: the file, its parsed JSON (8 bytes per byte of text), its buffers, decoded
  // accessors and output streams (an estimate that is checked before each allocation). CapacityExceeded
  // beyond it.
  uint64_t maxMemoryBytes = kDefaultImportMemoryBytes;
  // Mesh instances the import may create: importGltfScene's ImportedInstance records (one per node mesh
  // instance and material group, EXT_mesh_gpu_instancing instances included), importGltfMesh's copies of a
  // node's mesh. CapacityExceeded beyond it, before the instances are built.
  uint64_t maxInstances = kDefaultMaxInstances;
  // Required extensions to import anyway, as if the file only used them ("*": every one); each is still warned
  // about. Without it a required extension visbuf does not read is refused (gltf_extensions.h).
  std::vector<std::string> ignoreRequiredExtensions;
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

// ---------------------------------------------------------------------------------------------------------
// Scene import: the node hierarchy kept as instances.
//
// importGltfScene() walks the same default scene as importGltfMesh() (same roots, transforms, attribute rules
// and errors) but does not bake transforms into vertices:
//   - Meshes: one MeshSource per (glTF mesh, material) group: the primitives of a glTF mesh that share a
//     material are concatenated in object space; a mesh whose primitives use 3 materials gives 3 sources.
//     A mesh used by many nodes is decoded and stored once.
//   - Instances: every node that references a mesh gives one instance per material group:
//     (mesh index, material index, world transform as a dmat4, composed in double precision).
//   - Mirrored instances (det of the world 3x3 < 0): the renderer has a single front-face setting
//     (counter-clockwise), so such instances use a *mirrored mesh variant*: a second MeshSource with the same
//     vertices and normals whose triangles have their 2nd and 3rd index swapped. Under the mirroring
//     transform those triangles are counter-clockwise again, and the object-space normals (transformed with
//     the instance) still point outwards. The variant is created once per (mesh, material, morph weights),
//     shared by every mirrored instance of it; ImportedMesh::mirrored marks it. Its tangents have w negated:
//     a shader computes the world bitangent as cross(worldNormal, worldTangent) * w with worldTangent =
//     M * tangent, and under a mirroring M that cross product flips, so the variant carries the flip.
//   - Morph weights: a node whose weights differ from the mesh's gets its own mesh variant (weights are baked
//     into the vertices, as importGltfMesh does).
//   - Animated morph targets: a node whose weights a clip animates (a "weights" channel) keeps its mesh's
//     targets instead: MeshSource::morphTargets holds the POSITION, NORMAL and TANGENT deltas (object space,
//     zero for primitives without a target or an attribute), the vertices are the base shape (weights 0) and
//     MeshSource::morphWeights the node's (else the mesh's) default weights, padded with 0 to the target count
//     (warning on a mismatch). Its instances have `morphed` set. An unskinned one becomes skinned by a skin of
//     its own appended to ImportedScene::skins ("morph <node name>": one joint, the node itself, identity
//     inverse bind) with every vertex on joint 0, weight 1: skinning by global(node) is the node transform.
//   - Zero-determinant (degenerate, |det| < 1e-30 as validateScene() has it) instances are skipped with a
//     warning (they cover no pixels).
//   - Materials: every glTF material, in file order (so glTF material i is materials[i]): base colour factor
//     (linear RGBA), metallic and roughness factors, emissive factor, occlusion strength (all clamped to
//     [0,1] with a warning), normal scale, KHR_materials_emissive_strength (finite, >= 0), alpha mode and
//     cutoff, double-sided; and five texture references (base colour, metallic-roughness, normal, occlusion,
//     emissive), each with texture index, image index, image URI, TEXCOORD set (0 or 1; higher sets warn and
//     use 0), sampler (wrap S/T, mag/min/mip filter; undefined filters are trilinear) and
//     KHR_texture_transform as a 3x2 matrix (its texCoord overrides the set). A KHR_texture_basisu texture
//     refers to its fallback `source` image (its KTX2 image is never used); with none, the reference has no
//     image and a warning names the extension and the texture. Primitives without a material
//     use a "default" material (glTF's: white, opaque, metallic 1, roughness 1) appended after the file's
//     materials, only when needed.
//   - Images: every glTF image, in file order (glTF image i is images[i]), NOT decoded: the encoded bytes of
//     embedded images (bufferView, range-checked, or data: URI) or, for external files, the path resolved
//     by the URI rule (uri_resolver.h; a uri outside the allowed folders fails the import) (the file is not
//     opened here; texture_bake.h decodes all of them).
//   - Skinning: JOINTS_0 (VEC4 u8/u16) and WEIGHTS_0 (VEC4 float or normalized u8/u16) become
//     MeshSource::joints / weights; JOINTS_1 / WEIGHTS_1 (same formats; both or neither, MalformedInput
//     otherwise) become joints1 / weights1, influences 5-8. Weights are renormalised to sum 1 over all of a
//     vertex's influences (4 or 8); a vertex whose weights are all 0 gets weight 1 on its first slot (warning);
//     slots with weight 0 get joint 0. A mesh whose primitives mix 4 and 8 influences pads the 4-influence
//     vertices' slots 5-8 with weight 0. Meshes stay in rest pose (bind shape) in object space.
//   - Skins (only when the file has skins or animations, else nodes/skins/animations stay empty):
//     ImportedScene::nodes is every glTF node in file order (parent, rest TRS or matrix), so joint and
//     channel node indices are glTF node indices. Skins keep their joints, inverse bind matrices (identity
//     when absent; extra matrices beyond the joint count ignored) and skeleton. An instance of a node with a
//     skin has ImportedInstance::skin set. glTF ignores the skinned node's own transform: skinned vertices are
//     sum_i w_i * global(joint_i) * inverseBind_i * p, in world space (animation.h). The instance transform
//     (the node's world matrix) is kept for rest-pose drawing and must not be applied to skinned vertices;
//     mirrored variants of skinned meshes are chosen by that node transform too (for the usual files, whose
//     bind pose reproduces the node transform, it has the same handedness as the joint matrices).
//   - Animations: every clip with its channels (translation / rotation / scale / weights) and samplers
//     (LINEAR, STEP, CUBICSPLINE; rotations may be normalized integers). A sampler's times are the input
//     accessor (finite, strictly increasing), its values the output accessor, whose element count must be
//     keys x (3 for CUBICSPLINE, else 1) [x morph target count for weights]. Channels without a target node,
//     with an unknown path, or animating the weights of a node without morph targets are ignored (warning).
//   - Rigid node animation: an instance of an unskinned node that a translation / rotation / scale channel
//     moves (the channel targets the node or one of its ancestors, e.g. CesiumMilkTruck's wheels) and whose
//     morph weights no clip animates is a plain instance with ImportedInstance::rigid set: buildImportedScene()
//     makes it a RigidObject (scene.h) placed by the node's animated global matrix. An unskinned node whose
//     weights a clip animates gets a one-joint skin whose joint is the node itself (identity inverse bind):
//     every vertex has joint 0 with weight 1, so skinning by global(node) also plays its TRS channels exactly.
// Errors: as importGltfMesh(), plus MalformedInput for a primitive's material index that does not exist, for
// non-finite material factors or texture transforms, for texture / sampler indices that do not exist, for
// an image bufferView that does not exist or runs past its buffer, and for skin / animation data that cannot
// be evaluated: a joint node or skin that does not exist, a joint index (JOINTS_0, weight > 0) not below the
// skin's joint count, negative or non-finite weights, a skinned node's primitive without JOINTS_0 / WEIGHTS_0,
// inverse bind matrices that are fewer than the joints, non-finite or not affine, a child listed by two
// parents or a cycle anywhere in the node graph, non-increasing or non-finite key times, an output count that
// does not match the keys and interpolation, non-finite values, an unknown interpolation, an animated node
// that has a matrix. Messages name the node / skin / animation, sampler or channel and the accessor.
struct ImportedMesh {
  MeshSource source;      // object space; name: "<mesh name>" [+ "/<material name>"] [+ " (mirrored)"]
  int32_t gltfMesh = -1;  // source glTF mesh index
  uint32_t material = 0;  // index into ImportedScene::materials used by every instance of this mesh
  bool mirrored = false;  // winding flipped (for instances with a negative-determinant transform)
};

struct ImportedInstance {
  uint32_t mesh = 0;          // into ImportedScene::meshes
  uint32_t material = 0;      // into ImportedScene::materials (== meshes[mesh].material)
  glm::dmat4 transform{1.0};  // object -> world, double precision, finite, |det| >= 1e-30
  int32_t node = -1;          // source glTF node index
  int32_t skin = -1;          // into ImportedScene::skins when the node is skinned (then `transform` is not
                              // applied to the skinned vertices), -1 otherwise
  bool morphed = false;       // the mesh keeps its morph targets, driven by `node`'s animated weights
  bool rigid = false;         // unskinned, not morphed, and a TRS channel moves `node` or an ancestor of it
};

// A glTF image as found in the file, not decoded.
struct ImportedImage {
  std::string name;            // the image's name, else its URI, else "image N"
  std::string uri;             // as written in the glTF; empty for embedded images
  std::string path;            // external file: the URI resolved by the URI rule (uri_resolver.h): absolute,
                               // canonical (no links, no "..") and inside the allowed folders
  std::string mimeType;        // as declared (may be empty)
  std::vector<uint8_t> bytes;  // embedded image (bufferView or data: URI): the encoded file
  // An image the texture bake derived (converted spec-gloss textures, texture_bake.h): width x height RGBA8 codes
  // (rows top first; sRGB RGB for colour slots), no file. Empty for every image of a glTF file.
  std::vector<uint8_t> rgba8;
  uint32_t width = 0, height = 0;
};

struct ImportedScene {
  std::string name;  // file name without its extension
  std::vector<ImportedMesh> meshes;
  std::vector<Material> materials;
  std::vector<ImportedInstance> instances;
  std::vector<ImportedImage> images;  // glTF image i is images[i]
  // Animation data (empty when the file has neither skins nor animations).
  std::vector<SceneNode> nodes;  // every glTF node, in file order
  std::vector<Skin> skins;
  std::vector<AnimationClip> animations;
  // KHR_lights_punctual lights of the default scene's nodes (scene/light.h): point, spot and directional, at
  // their node's world position, spot and directional ones shining along the node's -Z (the world matrix's
  // linear part, renormalised); range and intensity are not scaled by the node, as the extension says; a
  // directional light's range is ignored. MalformedInput, naming the node and the light: a light index that
  // does not exist, a colour without 3 elements, a negative or non-finite range, intensity or colour, spot cone
  // angles outside 0 <= innerConeAngle < outerConeAngle <= pi/2, a node transform that maps -Z to a zero
  // direction. Lights of unknown type are skipped with a warning.
  std::vector<PointLight> pointLights;
  // The cameras of the default scene's nodes, in the order the nodes are visited (gltf_cameras.cpp): each placed
  // by its node's world matrix at rest, scale removed; named by the camera, else by its node. MalformedInput,
  // naming node and camera, for values glTF forbids (yfov outside (0, pi), znear <= 0 perspective or < 0
  // orthographic, zfar <= znear, aspectRatio, xmag or ymag <= 0, non-finite values); unknown types are skipped
  // with a warning.
  std::vector<NamedCamera> cameras;
};

// Imports the default scene of the glTF file at `path` as meshes + materials + instances (see above).
// `report` may be null; its primitive counts are per primitive instance, as for importGltfMesh().
Result<ImportedScene> importGltfScene(const std::string& path, const GltfImportOptions& options = {},
                                      GltfImportReport* report = nullptr);

}  // namespace visbuf
