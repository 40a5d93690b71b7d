"""glTF documents that lie in their numbers or ask for far more than they hold, and files that are not glTF.

- Integers tinygltf would narrow (2^32 + a valid value reads back as that value, 2^62 as 0), negative indices and
  offsets, numbers written as strings, wrong JSON types: refused naming the JSON path, in every kind of object.
- A few hundred bytes that ask for 10^7 EXT_mesh_gpu_instancing instances, 3,000 primitives or 5,000 morph
  targets sharing one accessor: a clean refusal naming the budget or a correct result, well inside the caps.
- An .obj, an image, an empty file, a pack, a JSON array: "not a glTF file" (or "is a visbuf pack"), never a
  JSON parser's message.
"""
import base64
import copy
import json
import os
import struct

W32 = 1 << 32


def base_doc():
    positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
    data = positions + indices
    return {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "nodes": [{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [2, 0, 0]}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }


def with_textures(d):
    d["samplers"] = [{"wrapS": 10497}]
    d["images"] = [{"uri": "missing.png"}]
    d["textures"] = [{"sampler": 0, "source": 0}]
    return d


def with_animation(d):
    d["animations"] = [{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
                        "samplers": [{"input": 0, "output": 0}]}]
    return d


def with_skin(d):
    d["skins"] = [{"joints": [1]}]
    return d


def with_sparse(d):
    d["accessors"][0]["sparse"] = {"count": 1, "indices": {"bufferView": 1, "componentType": 5123},
                                   "values": {"bufferView": 0}}
    return d


def set_path(d, path, value):
    """path: a list of keys / indices, the last one set to value."""
    node = d
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return d


# (case, preparation, JSON path to set, value, message regex after "doc.gltf: ").
NUMBER_CASES = [
    # Wide integers that tinygltf would wrap into valid values.
    ("wide_node_child", None, ["nodes", 0, "children", 0], W32 + 1, r"nodes\[0\]\.children\[0\]: 4294967297 is not a valid index"),
    ("wide_scene_node", None, ["scenes", 0, "nodes", 0], W32, r"scenes\[0\]\.nodes\[0\]: 4294967296 is not a valid index"),
    ("wide_root_scene", None, ["scene"], W32, r"scene: 4294967296 is not a valid index"),
    ("wide_node_mesh", None, ["nodes", 1, "mesh"], W32, r"nodes\[1\]\.mesh: 4294967296 is not a valid index"),
    ("wide_prim_indices", None, ["meshes", 0, "primitives", 0, "indices"], W32 + 1,
     r"meshes\[0\]\.primitives\[0\]\.indices: 4294967297 is not a valid index"),
    ("wide_prim_mode", None, ["meshes", 0, "primitives", 0, "mode"], W32 + 4,
     r"meshes\[0\]\.primitives\[0\]\.mode: 4294967300 is not one of"),
    ("wide_component_type", None, ["accessors", 0, "componentType"], W32 + 5126,
     r"accessors\[0\]\.componentType: 4294972422 is not one of"),
    ("wide_accessor_count", None, ["accessors", 0, "count"], 1 << 62, r"accessors\[0\]\.count: 4611686018427387904 is not a valid count"),
    ("wide_sparse_offset", with_sparse, ["accessors", 0, "sparse", "values", "byteOffset"], 1 << 62,
     r"accessors\[0\]\.sparse\.values\.byteOffset: 4611686018427387904 is not a valid byte offset"),
    ("wide_sparse_count", with_sparse, ["accessors", 0, "sparse", "count"], W32 + 1,
     r"accessors\[0\]\.sparse\.count: 4294967297 is not a valid count"),
    ("wide_view_offset", None, ["bufferViews", 1, "byteOffset"], 1 << 64, r"bufferViews\[1\]\.byteOffset: .* is not a valid byte offset"),
    ("wide_view_buffer", None, ["bufferViews", 0, "buffer"], W32, r"bufferViews\[0\]\.buffer: 4294967296 is not a valid index"),
    ("wide_view_stride", None, ["bufferViews", 0, "byteStride"], W32 + 12, r"bufferViews\[0\]\.byteStride: 4294967308 is not a valid byte stride"),
    ("wide_texture_index", with_textures, ["materials", 0, "pbrMetallicRoughness", "baseColorTexture"], {"index": W32},
     r"materials\[0\]\.pbrMetallicRoughness\.baseColorTexture\.index: 4294967296 is not a valid index"),
    ("wide_texture_source", with_textures, ["textures", 0, "source"], W32, r"textures\[0\]\.source: 4294967296 is not a valid index"),
    ("wide_sampler_wrap", with_textures, ["samplers", 0, "wrapS"], W32 + 10497, r"samplers\[0\]\.wrapS: 4294977793 is not one of"),
    ("wide_channel_sampler", with_animation, ["animations", 0, "channels", 0, "sampler"], W32,
     r"animations\[0\]\.channels\[0\]\.sampler: 4294967296 is not a valid index; animations\[0\]\.samplers has 1 entry"),
    ("wide_channel_node", with_animation, ["animations", 0, "channels", 0, "target", "node"], W32 + 1,
     r"animations\[0\]\.channels\[0\]\.target\.node: 4294967297 is not a valid index"),
    ("wide_skin_joint", with_skin, ["skins", 0, "joints", 0], W32 + 1, r"skins\[0\]\.joints\[0\]: 4294967297 is not a valid index"),
    ("wide_light_index", None, ["nodes", 0, "extensions"], {"KHR_lights_punctual": {"light": W32}},
     r"nodes\[0\]\.extensions\.KHR_lights_punctual\.light: 4294967296 is not a valid index"),
    ("wide_instancing_accessor", None, ["nodes", 0, "extensions"], {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": W32}}},
     r"nodes\[0\]\.extensions\.EXT_mesh_gpu_instancing\.attributes\.TRANSLATION: 4294967296 is not a valid index"),
    ("wide_transform_texcoord", with_textures, ["materials", 0, "emissiveTexture"],
     {"index": 0, "extensions": {"KHR_texture_transform": {"texCoord": W32}}},
     r"materials\[0\]\.emissiveTexture\.extensions\.KHR_texture_transform\.texCoord: 4294967296 is not a valid"),
    ("wide_meshopt_offset", None, ["bufferViews", 0, "extensions"],
     {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": 1 << 62, "byteLength": 4, "byteStride": 12, "count": 3,
                                  "mode": "ATTRIBUTES"}},
     r"bufferViews\[0\]\.extensions\.EXT_meshopt_compression\.byteOffset: 4611686018427387904 is not a valid byte offset"),
    # Negative values.
    ("negative_view_offset", None, ["bufferViews", 1, "byteOffset"], -4, r"bufferViews\[1\]\.byteOffset: -4 is not a valid byte offset"),
    ("negative_accessor_offset", None, ["accessors", 0, "byteOffset"], -12, r"accessors\[0\]\.byteOffset: -12 is not a valid byte offset"),
    ("negative_accessor_view", None, ["accessors", 0, "bufferView"], -1, r"accessors\[0\]\.bufferView: -1 is not a valid index"),
    ("negative_material", None, ["meshes", 0, "primitives", 0, "material"], -1,
     r"meshes\[0\]\.primitives\[0\]\.material: -1 is not a valid index"),
    ("negative_buffer_length", None, ["buffers", 0, "byteLength"], -44, r"buffers\[0\]\.byteLength: -44 is not a valid byte length"),
    ("negative_sparse_view", with_sparse, ["accessors", 0, "sparse", "indices", "bufferView"], -1,
     r"accessors\[0\]\.sparse\.indices\.bufferView: -1 is not a valid index"),
    ("negative_texcoord", with_textures, ["materials", 0, "normalTexture"], {"index": 0, "texCoord": -1},
     r"materials\[0\]\.normalTexture\.texCoord: -1 is not a valid texture coordinate set"),
    ("negative_anim_input", with_animation, ["animations", 0, "samplers", 0, "input"], -1,
     r"animations\[0\]\.samplers\[0\]\.input: -1 is not a valid index"),
    ("negative_skin_matrices", with_skin, ["skins", 0, "inverseBindMatrices"], -1,
     r"skins\[0\]\.inverseBindMatrices: -1 is not a valid index"),
    # Numbers written as strings, or other JSON types where numbers belong.
    ("string_translation", None, ["nodes", 0, "translation"], ["NaN", 0, 0], r"nodes\[0\]\.translation\[0\]: \"NaN\" is not a number"),
    ("string_rotation", None, ["nodes", 1, "rotation"], [0, 0, 0, "1"], r"nodes\[1\]\.rotation\[3\]: \"1\" is not a number"),
    ("object_scale", None, ["nodes", 1, "scale"], {"x": 1}, r"nodes\[1\]\.scale: expected an array of numbers, found an object"),
    ("short_matrix", None, ["nodes", 1, "matrix"], [1] * 15, r"nodes\[1\]\.matrix: has 15 elements, expected 16"),
    ("string_weights", None, ["nodes", 0, "weights"], ["0.5"], r"nodes\[0\]\.weights\[0\]: \"0.5\" is not a number"),
    ("string_base_color", None, ["materials", 0, "pbrMetallicRoughness", "baseColorFactor"], [1, 1, 1, "1"],
     r"materials\[0\]\.pbrMetallicRoughness\.baseColorFactor\[3\]: \"1\" is not a number"),
    ("string_metallic", None, ["materials", 0, "pbrMetallicRoughness", "metallicFactor"], "0",
     r"materials\[0\]\.pbrMetallicRoughness\.metallicFactor: \"0\" is not a number"),
    ("string_accessor_max", None, ["accessors", 0, "max"], [1, "1", 0], r"accessors\[0\]\.max\[1\]: \"1\" is not a number"),
    ("string_index", None, ["meshes", 0, "primitives", 0, "indices"], "1",
     r"meshes\[0\]\.primitives\[0\]\.indices: \"1\" is not a valid index"),
    ("string_camera_yfov", None, ["cameras"], [{"type": "perspective", "perspective": {"yfov": "0.8", "znear": 0.1}}],
     r"cameras\[0\]\.perspective\.yfov: \"0\.8\" is not a number"),
    ("string_light_intensity", None, ["extensions"], {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": "NaN"}]}},
     r"extensions\.KHR_lights_punctual\.lights\[0\]\.intensity: \"NaN\" is not a number"),
    ("string_texture_rotation", with_textures, ["materials", 0, "occlusionTexture"],
     {"index": 0, "extensions": {"KHR_texture_transform": {"rotation": "0.5"}}},
     r"materials\[0\]\.occlusionTexture\.extensions\.KHR_texture_transform\.rotation: \"0\.5\" is not a number"),
    ("string_emissive_strength", None, ["materials", 0, "extensions"],
     {"KHR_materials_emissive_strength": {"emissiveStrength": "5"}},
     r"materials\[0\]\.extensions\.KHR_materials_emissive_strength\.emissiveStrength: \"5\" is not a number"),
    ("fraction_node_mesh", None, ["nodes", 1, "mesh"], 0.5, r"nodes\[1\]\.mesh: 0\.5 is not a valid index"),
    ("array_children", None, ["nodes", 0, "children"], {"0": 1}, r"nodes\[0\]\.children: expected an array, found an object"),
]


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(doc, f)


def viewless_doc(count):
    """The base document plus accessor 2: `count` zero VEC3s with no bufferView (nothing in the file holds them)."""
    d = base_doc()
    d["accessors"].append({"componentType": 5126, "count": count, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]})
    return d


def cases(ctx):
    def bake(case, doc, check):
        root = ctx.folder(case)
        path = os.path.join(root, "doc.gltf")
        write_json(path, doc)
        out = os.path.join(root, "out.vbp")
        return root, out, ctx.visbuf_run(["bake", path, "-o", out], root)

    def refused(case, doc, pattern):
        root, out, outcome = bake(case, doc, None)
        if ctx.expect_error(case, outcome, pattern) and os.path.exists(out):
            ctx.fail(case, "a pack was written")

    def succeeds(case, doc):
        root, out, outcome = bake(case, doc, None)
        ctx.expect_ok(case, outcome, lambda: None if os.path.getsize(out) > 0 else "no pack written")

    yield "valid_base", lambda: succeeds("valid_base", base_doc())
    extras = base_doc()
    extras["nodes"][0]["extras"] = {"translation": "x", "mesh": -1, "children": [W32]}
    yield "extras_free_form", lambda: succeeds("extras_free_form", extras)

    for name, prepare, path, value, pattern in NUMBER_CASES:
        def run(name=name, prepare=prepare, path=path, value=value, pattern=pattern):
            d = base_doc()
            if prepare:
                d = prepare(d)
            refused(name, set_path(d, path, copy.deepcopy(value)), r"doc\.gltf: " + pattern)
        yield name, run

    # 10^7 instances from a 1 KB file: refused before any is built (the pack would hold 1.44 GB of objects).
    def instancing(case, count, expect_ok):
        d = viewless_doc(count)
        d["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
        d["nodes"][0]["extensions"] = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2}}}
        if expect_ok:
            succeeds(case, d)
        else:
            refused(case, d, r"10000000 instances pass the import's limit of 1048576 instances .*maxInstances")
    yield "instancing_1e7", lambda: instancing("instancing_1e7", 10 ** 7, False)
    yield "instancing_200k", lambda: instancing("instancing_200k", 200000, True)

    # 3,000 primitives sharing one accessor of 10^6 vertices: 36 GB of copies, refused before the first.
    def shared_primitives(case, vertices, expect_ok, count=3000):
        d = viewless_doc(vertices)
        d["meshes"][0]["primitives"] = [{"attributes": {"POSITION": 0}, "indices": 1}] + \
                                       [{"attributes": {"POSITION": 2}} for _ in range(count)]
        if expect_ok:
            succeeds(case, d)
        else:
            refused(case, d, r"mesh 0: its 3001 primitives need about \d+ bytes .*maxMemoryBytes")
    yield "primitives_3000_shared_1m", lambda: shared_primitives("primitives_3000_shared_1m", 10 ** 6, False)
    # (300 small ones import and bake; 3,000 coincident zero-area triangles are the mesh build's own case.)
    yield "primitives_300_shared_small", lambda: shared_primitives("primitives_300_shared_small", 30, True, 300)

    # 5,000 morph targets sharing one accessor: decoded once, the weights of the shared deltas summed. The morphed
    # primitive's POSITION is sparse: 10^6 vertices, of which the first three (one real triangle) are non-zero.
    def shared_targets(case, vertices, animated, pattern=None):
        d = viewless_doc(vertices)
        d["accessors"][2].pop("min")
        d["accessors"][2].pop("max")
        d["accessors"].append({"componentType": 5126, "count": vertices, "type": "VEC3",
                               "min": [0, 0, 0], "max": [1, 1, 0],
                               "sparse": {"count": 3, "indices": {"bufferView": 1, "componentType": 5123},
                                          "values": {"bufferView": 0}}})
        d["meshes"].append({"primitives": [{"attributes": {"POSITION": 3}, "indices": 1,
                                            "targets": [{"POSITION": 2} for _ in range(5000)]}],
                            "weights": [0.001] * 5000})
        d["nodes"].append({"mesh": 1, "translation": [0, 2, 0]})
        d["scenes"][0]["nodes"].append(2)
        if animated:
            d["accessors"].append({"componentType": 5126, "count": 1, "type": "SCALAR", "min": [0], "max": [0]})
            d["accessors"].append({"componentType": 5126, "count": 5000, "type": "SCALAR"})
            d["animations"] = [{"channels": [{"sampler": 0, "target": {"node": 2, "path": "weights"}}],
                                "samplers": [{"input": 4, "output": 5}]}]
        if pattern:
            refused(case, d, pattern)
        else:
            succeeds(case, d)
    yield "morph_5000_shared", lambda: shared_targets("morph_5000_shared", 10 ** 6, False)
    yield "morph_5000_shared_animated", lambda: shared_targets(
        "morph_5000_shared_animated", 10 ** 6, True, r"5000 animated morph targets: needs \d+ more bytes.*maxMemoryBytes")

    # 5,000 targets, each its own accessor of 10^6 zero deltas (no bufferView): 60 GB of decoded deltas from a
    # 300 KB file, refused before the first is decoded.
    def distinct_targets():
        case = "morph_5000_distinct_viewless"
        d = viewless_doc(3)
        first = len(d["accessors"])
        d["accessors"] += [{"componentType": 5126, "count": 10 ** 6, "type": "VEC3"} for _ in range(5000)]
        d["accessors"].append({"componentType": 5126, "count": 10 ** 6, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]})
        d["meshes"][0]["primitives"] = [{"attributes": {"POSITION": len(d["accessors"]) - 1},
                                         "targets": [{"POSITION": first + t} for t in range(5000)]}]
        d["meshes"][0]["weights"] = [0.0] * 5000
        refused(case, d, r"mesh 0: its 1 primitives need about \d+ bytes .*maxMemoryBytes")
    yield "morph_5000_distinct_viewless", distinct_targets

    # Files that are not glTF, whatever their name.
    def not_gltf(case, name, data, pattern):
        root = ctx.folder(case)
        path = os.path.join(root, name)
        with open(path, "wb") as f:
            f.write(data)
        outcome = ctx.visbuf_run(["bake", path, "-o", os.path.join(root, "out.vbp")], root)
        if ctx.expect_error(case, outcome, pattern) and "parse" in outcome.text:
            ctx.fail(case, "the message is a parser's", outcome)
    wrong = [
        ("obj_file", "cube.obj", b"# cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", r"cube\.obj: not a glTF file"),
        ("obj_named_gltf", "cube.gltf", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", r"cube\.gltf: not a glTF file"),
        ("png_file", "image.gltf", b"\x89PNG\r\n\x1a\n" + b"\0" * 32, r"image\.gltf: not a glTF file \(it is a PNG image\)"),
        ("jpeg_named_glb", "photo.glb", b"\xff\xd8\xff\xe0\0\x10JFIF\0" + b"\0" * 32, r"photo\.glb: not a glTF file \(it is a JPEG image\)"),
        ("empty_gltf", "empty.gltf", b"", r"empty\.gltf: not a glTF file \(the file is empty\)"),
        ("json_array", "list.gltf", b"[1, 2, 3]", r"list\.gltf: not a glTF file \(a JSON array"),
        ("binary_noise", "noise.gltf", bytes(range(1, 256)), r"noise\.gltf: not a glTF file"),
    ]
    for case, name, data, pattern in wrong:
        yield case, (lambda case=case, name=name, data=data, pattern=pattern: not_gltf(case, name, data, pattern))

    # A pack given where a glTF is expected (render --scene takes packs; the importer says so).
    def pack_to_importer():
        case = "pack_named_gltf"
        root = ctx.folder(case)
        src = os.path.join(root, "tri.gltf")
        write_json(src, base_doc())
        pack = os.path.join(root, "tri.vbp")
        made = ctx.visbuf_run(["bake", src, "-o", pack], root)
        if made.code != 0:
            ctx.fail(case, "could not bake the base document", made)
            return
        renamed = os.path.join(root, "pack.gltf")
        os.rename(pack, renamed)
        outcome = ctx.visbuf_run(["render", "--mesh", renamed, "-o", os.path.join(root, "x.png")], root)
        ctx.expect_error(case, outcome, r"pack\.gltf'?: .*is a visbuf pack")
    yield "pack_named_gltf", pack_to_importer
