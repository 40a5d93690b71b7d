"""KHR_draco_mesh_compression streams that lie (engine/asset/gltf_draco.cpp): a valid stream is made at run time
with Debian's draco_transcoder from assets/BoxInterleaved (the `draco` package, scripts/deps.txt), then cut,
corrupted, given header counts of a billion faces, paired with accessors whose counts, ids and types lie, or
with counts that would make the decode a bomb. Each through `visbuf bake`: a clean error naming the problem (or,
for random corruption, a correct result or a clean error), within the suite's caps (60 s, 2 GiB)."""
import json
import os
import random
import shutil
import struct
import subprocess

EXT = "KHR_draco_mesh_compression"


def _varint(value):
    out = b""
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out += bytes([byte | 0x80])
        else:
            return out + bytes([byte])


def _read_varint(data, at):
    value, shift = 0, 0
    while True:
        byte = data[at]
        value |= (byte & 0x7F) << shift
        at += 1
        shift += 7
        if not byte & 0x80:
            return value, at


def _parse_glb(data):
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    at = 20 + json_len
    bin_len = struct.unpack_from("<I", data, at)[0]
    return doc, data[at + 8:at + 8 + bin_len]


class Base:
    """The transcoded box: its document (one Draco primitive), its buffer, and where the Draco stream lies."""

    def __init__(self, work, repo):
        tool = shutil.which("draco_transcoder")
        if tool is None:
            raise RuntimeError("draco_transcoder not found (scripts/deps.txt: the `draco` package)")
        src = os.path.join(repo, "assets", "BoxInterleaved", "glTF", "BoxInterleaved.gltf")
        out = os.path.join(work, "box.draco.glb")
        subprocess.run([tool, "-i", src, "-o", out, "-qp", "16"], check=True, stdout=subprocess.DEVNULL)
        with open(out, "rb") as f:
            self.doc, self.bin = _parse_glb(f.read())
        prim = self.doc["meshes"][0]["primitives"][0]
        view = self.doc["bufferViews"][prim["extensions"][EXT]["bufferView"]]
        start = view.get("byteOffset", 0)
        self.stream = self.bin[start:start + view["byteLength"]]

    def write(self, folder, stream=None, edit=None):
        """Writes box.gltf + box.bin: the document with the Draco stream replaced by `stream` (appended as a new
        bufferView) and `edit(doc, prim, ext)` applied. Returns the .gltf path."""
        doc = json.loads(json.dumps(self.doc))
        blob = bytearray(self.bin)
        prim = doc["meshes"][0]["primitives"][0]
        ext = prim["extensions"][EXT]
        if stream is not None:
            blob += b"\0" * (-len(blob) % 4)
            doc["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": max(len(stream), 1)})
            blob += stream if stream else b"\0"
            ext["bufferView"] = len(doc["bufferViews"]) - 1
        if edit:
            edit(doc, prim, ext)
        doc["buffers"] = [{"uri": "box.bin", "byteLength": len(blob)}]
        with open(os.path.join(folder, "box.bin"), "wb") as f:
            f.write(blob)
        path = os.path.join(folder, "box.gltf")
        with open(path, "w") as f:
            json.dump(doc, f)
        return path

    def header_counts(self):
        """Offsets of the edgebreaker header's varints: encoded vertices and faces (bitstream 2.2)."""
        s = self.stream
        assert s[:5] == b"DRACO" and s[7] == 1 and s[8] == 1, "expected an edgebreaker mesh"
        at = 11 + 1  # header (magic, version, encoder type and method, flags), then the traversal decoder type
        vertices, after_vertices = _read_varint(s, at)
        faces, after_faces = _read_varint(s, after_vertices)
        return (at, after_vertices, vertices), (after_vertices, after_faces, faces)


def cases(ctx):
    state = {}

    def base():
        if "base" not in state:
            state["base"] = Base(ctx.folder("base"), ctx.repo)
        return state["base"]

    def bake(case, pattern, stream=None, edit=None, ok=False, clean=False):
        root = ctx.folder(case)
        path = base().write(root, stream, edit)
        outcome = ctx.visbuf_run(["bake", path, "-o", os.path.join(root, "out.vbp")], root)
        if ok:
            ctx.expect_ok(case, outcome)
        elif clean:
            ctx.expect_clean(case, outcome, pattern)
        else:
            ctx.expect_error(case, outcome, pattern)

    yield "valid_stream_bakes", lambda: bake("valid_stream_bakes", None, ok=True)

    # The stream itself.
    yield "truncated_stream", lambda: bake("truncated_stream", r"Draco stream", base().stream[:len(base().stream) // 2])
    yield "header_only", lambda: bake("header_only", r"Draco stream", base().stream[:16])
    yield "not_draco", lambda: bake("not_draco", r"Draco stream", b"\0" * 64)
    yield "point_cloud", lambda: bake("point_cloud", r"Draco stream",
                                      base().stream[:7] + b"\0" + base().stream[8:])

    def lie_header(which, value):
        (vs, ve, _), (fs, fe, _) = base().header_counts()
        s = base().stream
        return s[:vs] + _varint(value) + s[ve:] if which == "vertices" else s[:fs] + _varint(value) + s[fe:]

    # Header counts far beyond what the accessors (and the stream's length) allow: the decoder's allocations
    # are stopped at the working set charged for the accessors' counts.
    # (libdraco 1.5.5 refuses these itself, before allocating.)
    for which, value in (("faces", 0x3FFFFFFF), ("faces", 13), ("vertices", 0xFFFFFFF0), ("vertices", 1 << 28)):
        name = f"header_{which}_{value}"
        yield name, (lambda name=name, which=which, value=value:
                     bake(name, r"Draco stream", lie_header(which, value)))

    # A real stream of 80,000 faces (a 200 x 200 grid, draco_encoder) behind accessors that declare the box's 12
    # faces and 24 points: the decoder is stopped at the box's working set instead of decoding the grid.
    def grid_stream():
        root = ctx.folder("grid")
        obj, drc = os.path.join(root, "grid.obj"), os.path.join(root, "grid.drc")
        n = 200
        with open(obj, "w") as f:
            f.writelines(f"v {x} {y} 0\n" for y in range(n + 1) for x in range(n + 1))
            for y in range(n):
                for x in range(n):
                    a = y * (n + 1) + x + 1
                    f.write(f"f {a} {a + 1} {a + n + 2}\nf {a} {a + n + 2} {a + n + 1}\n")
        subprocess.run([shutil.which("draco_encoder") or "draco_encoder", "-i", obj, "-o", drc, "-cl", "10"],
                       check=True, stdout=subprocess.DEVNULL)
        with open(drc, "rb") as f:
            return f.read()

    def position_only(doc, prim, ext):  # draco's OBJ reader gives POSITION unique id 0
        prim["attributes"].pop("NORMAL")
        ext["attributes"] = {"POSITION": 0}
    yield "stream_larger_than_accessors", lambda: bake("stream_larger_than_accessors",
                                                       r"Draco stream .*the decoder asked for more than \d+ bytes",
                                                       grid_stream(), edit=position_only)

    # Accessors that lie about what the stream holds.
    def set_count(semantic, delta):
        def edit(doc, prim, ext):
            acc = doc["accessors"][prim["indices"] if semantic == "indices" else prim["attributes"][semantic]]
            acc["count"] += delta
        return edit
    yield "indices_count_lies", lambda: bake("indices_count_lies", r"decodes to .* faces", edit=set_count("indices", 3))
    yield "indices_count_not_triangles", lambda: bake("indices_count_not_triangles", r"not a multiple of 3",
                                                      edit=set_count("indices", 1))
    yield "position_count_lies", lambda: bake("position_count_lies", r"count",
                                              edit=set_count("POSITION", 5))

    def all_counts(points, indices):
        def edit(doc, prim, ext):
            for semantic in ext["attributes"]:
                doc["accessors"][prim["attributes"][semantic]]["count"] = points
            doc["accessors"][prim["indices"]]["count"] = indices
        return edit
    # Counts that agree with each other (and with a lying header) but not with the stream's few hundred bytes.
    yield "bomb_counts_in_budget", lambda: bake("bomb_counts_in_budget", r"implausible for its size",
                                                lie_header("faces", 1 << 22), edit=all_counts(1 << 22, 3 << 22))
    yield "bomb_counts_past_budget", lambda: bake("bomb_counts_past_budget", r"budget",
                                                  edit=all_counts(1 << 40, 3 << 40))

    # The extension's attribute map.
    def set_attr(semantic, value):
        def edit(doc, prim, ext):
            ext["attributes"][semantic] = value
        return edit
    yield "id_not_in_stream", lambda: bake("id_not_in_stream", r"no attribute with unique id 7",
                                           edit=set_attr("NORMAL", 7))
    yield "id_twice", lambda: bake("id_twice", r"named twice",
                                   edit=lambda d, p, e: e["attributes"].update(NORMAL=e["attributes"]["POSITION"]))
    yield "id_negative", lambda: bake("id_negative", r"Draco attribute id|attribute id", edit=set_attr("NORMAL", -1))
    yield "id_huge", lambda: bake("id_huge", r"Draco attribute id|attribute id", edit=set_attr("NORMAL", 1e30))
    yield "semantic_not_in_primitive", lambda: bake("semantic_not_in_primitive", r"TEXCOORD_3 is not an attribute",
                                                    edit=set_attr("TEXCOORD_3", 5))
    yield "attributes_not_object", lambda: bake("attributes_not_object", r"attributes",
                                                edit=lambda d, p, e: e.update(attributes=[0, 1]))
    yield "buffer_view_missing", lambda: bake("buffer_view_missing", r"bufferView",
                                              edit=lambda d, p, e: e.update(bufferView=99))

    def swap_types(doc, prim, ext):  # NORMAL read as VEC2: Draco's attribute has 3 components
        doc["accessors"][prim["attributes"]["NORMAL"]]["type"] = "VEC2"
    yield "component_count_lies", lambda: bake("component_count_lies", r"components", edit=swap_types)
    yield "no_indices", lambda: bake("no_indices", r"needs an indices accessor",
                                     edit=lambda d, p, e: p.pop("indices"))
    yield "strip_mode", lambda: bake("strip_mode", r"only TRIANGLES", edit=lambda d, p, e: p.update(mode=5))

    def tiny_indices(doc, prim, ext):  # faces decoded into UNSIGNED_BYTE: fits (24 points); SCALAR FLOAT does not
        doc["accessors"][prim["indices"]]["componentType"] = 5126
    yield "indices_float", lambda: bake("indices_float", r"indices must be", edit=tiny_indices)

    # Random corruption of the valid stream (seeded): a correct bake or a clean error, never a crash or a hang.
    def corrupt(seed):
        rng = random.Random(seed)
        s = bytearray(base().stream)
        for _ in range(rng.randint(1, 4)):
            at = rng.randrange(11, len(s))
            s[at] = rng.randrange(256)
        return bytes(s)
    for seed in range(24):
        name = f"corrupt_{seed}"
        yield name, (lambda name=name, seed=seed: bake(name, r"Draco stream|error", corrupt(seed), clean=True))
