#!/usr/bin/env python3
"""Writes the hostile glTF files of this folder (docs/security.md). Run it from anywhere:

    python3 tests/data/hostile/make_hostile.py

The files are small and hand-made; what each one must do is asserted by tests/cli_hostile.py (visbuf bake)
and tests/unit/test_hostile_assets.cpp (the engine). Files that name something outside their folder point at
"../canary.bin" / "../canary.png": the tests copy this folder into a temporary one and put the canary next
to the copy, so the canary is outside the asset's folder. "*.gltf.in" files are templates whose "@CANARY@" /
"@CANARY_PNG@" the tests replace with the canary's absolute path. Symbolic links and FIFOs cannot live in a
repository: the tests create them ("link.bin", "up/", "link.png", "fifo.bin", "fifo.png").
"""
import base64
import json
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))

# The canary the tests write outside the asset's folder: 12 bytes, read as 3 RGBA8 vertex colours.
CANARY_BYTES = 12


def data_uri(raw):
    return "data:application/octet-stream;base64," + base64.b64encode(raw).decode()


def triangle_doc(positions=(0, 0, 0, 1, 0, 0, 0, 1, 0)):
    """A one-triangle scene: buffer 0 holds positions (36 bytes) and uvs (24 bytes) as a data: URI."""
    raw = struct.pack("<9f", *positions) + struct.pack("<6f", 0, 0, 1, 0, 0, 1)
    lo = [min(positions[i::3]) for i in range(3)]
    hi = [max(positions[i::3]) for i in range(3)]
    return {
        "asset": {"version": "2.0", "generator": "visbuf tests/data/hostile/make_hostile.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "triangle"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
        "buffers": [{"byteLength": len(raw), "uri": data_uri(raw)}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
        ],
    }


def with_color_buffer(uri):
    """COLOR_0 (unorm8 VEC4, 3 vertices) read from an external buffer: if that buffer were read, its 12 bytes
    would land verbatim in the pack's vertex colours."""
    doc = triangle_doc()
    doc["buffers"].append({"byteLength": CANARY_BYTES, "uri": uri})
    doc["bufferViews"].append({"buffer": 1, "byteLength": CANARY_BYTES})
    doc["accessors"].append({"bufferView": 2, "componentType": 5121, "normalized": True, "count": 3, "type": "VEC4"})
    doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2
    return doc


def with_image(uri, slot="normalTexture"):
    """A material whose texture is the image at `uri` (a normal map: linear, so baked texels equal the file's)."""
    doc = triangle_doc()
    doc["images"] = [{"uri": uri}]
    doc["textures"] = [{"source": 0}]
    material = {"name": "hostile"}
    if slot == "baseColorTexture":
        material["pbrMetallicRoughness"] = {"baseColorTexture": {"index": 0}}
    else:
        material[slot] = {"index": 0}
    doc["materials"] = [material]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    return doc


def image_bomb_png():
    """16384 x 16384, 1-bit grey, every pixel 0: a complete, valid PNG of ~33 KB that decodes to 268 Mpixel
    (4 GiB as RGBA float)."""
    side = 16384
    row = b"\x00" + bytes(side // 8)  # filter byte + 2048 bytes of 1-bit pixels
    compressor = zlib.compressobj(9)
    idat = b"".join(compressor.compress(row) for _ in range(side)) + compressor.flush()

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    ihdr = struct.pack(">IIBBBBB", side, side, 1, 0, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


def truncated_jpeg():
    """truncated.jpg is committed: a 32x32 JPEG of noise (oiiotool --pattern noise:type=uniform:seed=7 32x32 3
    -d uint8 -o n.jpg, 2276 bytes) cut halfway through its scan data (the first 1639 bytes; no FF D9 end
    marker). Decoders pad such a file with grey and merely warn ("Premature end of JPEG file")."""
    if not os.path.exists(os.path.join(HERE, "truncated.jpg")):
        raise SystemExit("tests/data/hostile/truncated.jpg is missing (see truncated_jpeg())")


def write_json(name, doc):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def main():
    # Path traversal through a buffer uri, four ways.
    write_json("buffer_traversal.gltf", with_color_buffer("../canary.bin"))
    write_json("buffer_traversal_encoded.gltf", with_color_buffer("..%2Fcanary.bin"))
    write_json("buffer_absolute.gltf.in", with_color_buffer("@CANARY@"))
    write_json("buffer_symlink.gltf", with_color_buffer("link.bin"))        # link.bin -> ../canary.bin
    write_json("buffer_symlink_dir.gltf", with_color_buffer("up/canary.bin"))  # up -> ..
    # ... and through an image uri.
    write_json("image_traversal.gltf", with_image("../canary.png"))
    write_json("image_traversal_encoded.gltf", with_image("%2E%2E%2Fcanary.png"))
    write_json("image_absolute.gltf.in", with_image("@CANARY_PNG@"))
    write_json("image_symlink.gltf", with_image("link.png"))  # link.png -> ../canary.png
    # Decompression bomb.
    with open(os.path.join(HERE, "image_bomb.png"), "wb") as f:
        f.write(image_bomb_png())
    write_json("image_bomb.gltf", with_image("image_bomb.png", "baseColorTexture"))
    # A truncated JPEG (committed, see truncated_jpeg()).
    truncated_jpeg()
    write_json("truncated_jpeg.gltf", with_image("truncated.jpg", "baseColorTexture"))
    # FIFOs inside the folder (created by the tests).
    write_json("fifo_buffer.gltf", with_color_buffer("fifo.bin"))
    write_json("fifo_image.gltf", with_image("fifo.png"))
    # glTF 1.0.
    doc = triangle_doc()
    doc["asset"]["version"] = "1.0"
    write_json("version_1_0.gltf", doc)
    # A node cycle outside the scene: nodes 1 -> 2 -> 1, the scene only has node 0.
    doc = triangle_doc()
    doc["nodes"] += [{"name": "a", "children": [2]}, {"name": "b", "children": [1]}]
    write_json("node_cycle.gltf", doc)
    # Positions near the float maximum: every bound and distance overflows.
    write_json("huge_positions.gltf", triangle_doc((0, 0, 0, 3e38, 0, 0, 0, 3e38, 0)))


if __name__ == "__main__":
    main()
