"""GLB containers whose sizes lie, and inputs that are not glTF at all: each must be refused by name, at once,
without reading past what the file holds."""
import json
import os
import struct


def glb(json_bytes, bin_bytes=None, total=None, json_len=None, bin_len=None, magic=b"glTF", version=2):
    pad = (4 - len(json_bytes) % 4) % 4
    json_bytes += b" " * pad
    body = struct.pack("<I", len(json_bytes) if json_len is None else json_len) + b"JSON" + json_bytes
    if bin_bytes is not None:
        bpad = (4 - len(bin_bytes) % 4) % 4
        bin_bytes += b"\0" * bpad
        body += struct.pack("<I", len(bin_bytes) if bin_len is None else bin_len) + b"BIN\0" + bin_bytes
    length = 12 + len(body) if total is None else total
    return magic + struct.pack("<II", version, length) + body


DOC = json.dumps({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 12}],
                  "bufferViews": [{"buffer": 0, "byteLength": 12}],
                  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3",
                                 "min": [0, 0, 0], "max": [0, 0, 0]}],
                  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
                  "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}).encode()


def cases(ctx):
    def bake_bytes(case, name, data, pattern):
        root = ctx.folder(case)
        path = os.path.join(root, name)
        with open(path, "wb") as f:
            f.write(data)
        outcome = ctx.visbuf_run(["bake", path, "-o", os.path.join(root, "out.vbp")], root)
        if ctx.expect_error(case, outcome, pattern) and os.path.exists(os.path.join(root, "out.vbp")):
            ctx.fail(case, "a pack was written")

    lies = {
        "total_length_beyond_file": dict(total=1 << 31),
        "json_chunk_beyond_file": dict(json_len=1 << 30),
        "bin_chunk_beyond_file": dict(bin_len=(1 << 32) - 4),
        "bad_version": dict(version=1),
    }
    for case, kw in lies.items():
        yield case, (lambda case=case, kw=kw:
                     bake_bytes(case, "lie.glb", glb(DOC, b"\0" * 12, **kw), r"lie\.glb: .*(GLB|version|chunk|length)"))
    yield "bad_magic", lambda: bake_bytes("bad_magic", "magic.glb", glb(DOC, magic=b"gLTF"),
                                          r"magic\.glb: not a GLB file \(bad magic\)")
    yield "empty_file", lambda: bake_bytes("empty_file", "empty.gltf", b"", r"empty\.gltf")
