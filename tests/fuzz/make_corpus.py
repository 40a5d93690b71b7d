#!/usr/bin/env python3
"""Regenerates the committed seed corpus of the fuzz targets (tests/fuzz/corpus/<target>/).

    tests/fuzz/make_corpus.py --visbuf build-clang/tools/visbuf

Seeds are small on purpose (the whole corpus stays well under 300 KB): libFuzzer mutates them, and a short
input runs faster. Sources:
  fuzz_gltf_import   small sample files of the repository's assets/ (licences: assets/README.md), made
                     self-contained (GLB, or .gltf with data: URIs) since the target has one file to read,
                     plus a synthesised GLB that uses materials, textures (embedded PNG and data: URI),
                     samplers, KHR_texture_transform, lights, a camera and a mirrored node, a minimal .gltf, and a
                     synthesised .gltf with rigid node animation.
  fuzz_pack_reader   packs baked by `visbuf bake` from some of those glTF seeds (animated, skinned, textured,
                     rigid node animation, RGBA8 texels in a zstd section).
  fuzz_image_decode  tiny PNGs (every colour type, 16-bit, Adam7, palette + tRNS) written here, tiny JPEGs
                     (baseline with Exif + IPTC, greyscale, progressive, 4:2:0) written by oiiotool, and
                     regression_*: inputs that once crashed or exhausted memory, derived from those.
Needs python3, oiiotool (openimageio-tools) and a built visbuf. Overwrites the files it writes only.
"""
import argparse
import base64
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ASSETS = os.path.join(ROOT, "assets")
CORPUS = os.path.join(ROOT, "tests", "fuzz", "corpus")


def compact(doc):
    return json.dumps(doc, separators=(",", ":")).encode()


def pad4(b, fill=b"\0"):
    return b + fill * (-len(b) % 4)


def glb(doc, binary):
    js = pad4(compact(doc), b" ")
    out = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary is not None:
        binary = pad4(binary)
        out += struct.pack("<II", len(binary), 0x004E4942) + binary
    return struct.pack("<4sII", b"glTF", 2, 12 + len(out)) + out


def load_gltf(rel):
    path = os.path.join(ASSETS, rel)
    with open(path) as f:
        return json.load(f), os.path.dirname(path)


def to_glb(rel):
    """A .gltf with one external buffer -> GLB with that buffer as its BIN chunk."""
    doc, folder = load_gltf(rel)
    assert len(doc["buffers"]) == 1
    with open(os.path.join(folder, doc["buffers"][0]["uri"]), "rb") as f:
        data = f.read()
    del doc["buffers"][0]["uri"]
    return glb(doc, data)


def embedded(rel):
    """A .gltf whose external buffers become data: URIs."""
    doc, folder = load_gltf(rel)
    for b in doc["buffers"]:
        with open(os.path.join(folder, b["uri"]), "rb") as f:
            b["uri"] = "data:application/octet-stream;base64," + base64.b64encode(f.read()).decode()
    return compact(doc)


def copy(rel):
    with open(os.path.join(ASSETS, rel), "rb") as f:
        return f.read()


# --- PNG


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(width, height, color_type, depth, rows, interlace=0, extra=()):
    """rows: the raw, already filtered scanlines (each starting with its filter byte)."""
    ihdr = struct.pack(">IIBBBBB", width, height, depth, color_type, 0, 0, interlace)
    out = b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr)
    for kind, data in extra:
        out += png_chunk(kind, data)
    return out + png_chunk(b"IDAT", zlib.compress(rows, 9)) + png_chunk(b"IEND", b"")


def png_simple(width, height, color_type, depth, pixel, filter_type=0):
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[color_type]
    rows = b""
    for y in range(height):
        row = b"".join(pixel(x, y) for x in range(width))
        assert len(row) * 8 == width * channels * depth or depth < 8
        rows += bytes([filter_type]) + row
    return rows


def png_seeds():
    seeds = {}
    rgba = png_simple(2, 2, 6, 8, lambda x, y: bytes([255 * x, 255 * y, 128, 200]))
    seeds["rgba8_2x2.png"] = png(2, 2, 6, 8, rgba)
    rgb = png_simple(3, 2, 2, 8, lambda x, y: bytes([80 * x, 120 * y, 30]), filter_type=1)
    seeds["rgb8_3x2_sub.png"] = png(3, 2, 2, 8, rgb)
    grey = png_simple(4, 4, 0, 8, lambda x, y: bytes([16 * (x + 4 * y)]), filter_type=2)
    seeds["grey8_4x4_up.png"] = png(4, 4, 0, 8, grey)
    ga = png_simple(2, 2, 4, 8, lambda x, y: bytes([200, 100 * (x + y)]), filter_type=4)
    seeds["greyalpha8_2x2_paeth.png"] = png(2, 2, 4, 8, ga)
    pal = png_simple(4, 4, 3, 8, lambda x, y: bytes([(x + y) % 3]), filter_type=3)
    seeds["palette_4x4_trns.png"] = png(4, 4, 3, 8, pal, extra=[(b"PLTE", bytes([255, 0, 0, 0, 255, 0, 0, 0, 255])),
                                                               (b"tRNS", bytes([255, 128]))])
    rgb16 = png_simple(2, 2, 2, 16, lambda x, y: struct.pack(">HHH", 65535 * x, 30000, 1000 * y))
    seeds["rgb16_2x2_gama.png"] = png(2, 2, 2, 16, rgb16, extra=[(b"gAMA", struct.pack(">I", 45455))])
    seeds["grey1_3x1.png"] = png(3, 1, 0, 1, bytes([0, 0b10100000]))  # 1 bit: filter byte + one byte of pixels
    # Adam7, 8x8 RGB: the seven passes' scanlines in order (pass sizes for 8x8: 1x1, 1x1, 2x1, 2x2, 4x2, 4x4, 8x4).
    rows = b""
    for pw, ph in [(1, 1), (1, 1), (2, 1), (2, 2), (4, 2), (4, 4), (8, 4)]:
        for y in range(ph):
            rows += b"\0" + bytes([(37 * (x + y)) & 255 for x in range(pw) for _ in range(3)])
    seeds["rgb8_8x8_adam7.png"] = png(8, 8, 2, 8, rows, interlace=1)
    # Adam7, 3x3 RGBA 16-bit: passes 2 and 3 are empty (no rows at all); the others are 1x1, 1x1, 2x1, 1x2, 3x1.
    rows = b""
    for pw, ph in [(1, 1), (1, 1), (2, 1), (1, 2), (3, 1)]:
        for y in range(ph):
            rows += b"\0" + b"".join(struct.pack(">HHHH", 9000 * x, 60000, 300 * y, 65535 - x) for x in range(pw))
    seeds["rgba16_3x3_adam7.png"] = png(3, 3, 6, 16, rows, interlace=1)
    pal2 = b"\0\x1b\0\xe4"  # 2-bit palette, 4x2: filter byte + one packed byte a row
    seeds["palette2_4x2.png"] = png(4, 2, 3, 2, pal2, extra=[(b"PLTE", bytes(range(12)))])
    # Metadata chunks: a texture reads none of them (texture_decode_png.cpp skips all but PLTE / tRNS), and the
    # fuzzer should keep checking that.
    xmp = b"<x:xmpmeta xmlns:x='adobe:ns:meta/'>" + b"<a>" * 40 + b"</a>" * 40 + b"</x:xmpmeta>"
    key = b"XML:com.adobe.xmp\0"
    tiff = b"MM\0*\0\0\0\x08\0\x01" + struct.pack(">HHII", 0x8769, 4, 1, 8) + b"\0\0\0\0"
    seeds["rgba8_2x2_metadata.png"] = png(2, 2, 6, 8, rgba, extra=[
        (b"iTXt", key + b"\0\0\0\0" + xmp), (b"zTXt", key + b"\0" + zlib.compress(xmp)),
        (b"tEXt", b"Raw profile type exif\0\nexif\n" + str(len(tiff)).encode() + b"\n" + tiff.hex().encode()),
        (b"eXIf", tiff), (b"iCCP", b"icc\0\0" + zlib.compress(b"\0\0\x02\x0cappl" + b"\0" * 120)),
        (b"sRGB", b"\0"), (b"pHYs", bytes(9)), (b"vsBf", b"private")])
    return seeds


def jpeg_seeds(tmp):
    seeds = {}
    # --nosoftwareattrib: no command line (with its temporary path) in the metadata; the baseline seed carries an
    # Exif (APP1) and an IPTC (APP13) block on purpose, for OpenImageIO's metadata parsers.
    variants = [
        ("baseline_rgb_8x8.jpg", ["--pattern", "checker:width=2:height=2", "8x8", "3"],
         ["--caption", "visbuf fuzz seed", "--attrib", "IPTC:Keywords", "seed"]),
        ("grey_16x8.jpg", ["--pattern", "fill:top=0.1:bottom=0.9", "16x8", "1"], []),
        ("progressive_rgb_8x8.jpg", ["--pattern", "fill:topleft=1,0,0:topright=0,1,0:bottomleft=0,0,1:bottomright=1,1,1",
                                     "8x8", "3"], ["--attrib", "jpeg:progressive", "1"]),
        ("subsampled420_16x16.jpg", ["--pattern", "checker:width=4:height=4", "16x16", "3"],
         ["--attrib", "jpeg:subsampling", "4:2:0"]),
    ]
    for name, pattern, attribs in variants:
        out = os.path.join(tmp, name)
        subprocess.run(["oiiotool", "--nosoftwareattrib"] + pattern + attribs + ["--quality", "80", "-o", out],
                       check=True)
        with open(out, "rb") as f:
            seeds[name] = f.read()
    seeds.update(jpeg_regressions(seeds["baseline_rgb_8x8.jpg"], seeds["progressive_rgb_8x8.jpg"]))
    # The progressive seed with metadata segments after SOI: XMP (APP1), ICC (APP2), IPTC (APP13), a comment.
    def seg(marker, payload):
        return struct.pack(">BBH", 0xFF, marker, len(payload) + 2) + payload
    xmp = b"http://ns.adobe.com/xap/1.0/\0<x:xmpmeta>" + b"<a>" * 40 + b"</a>" * 40 + b"</x:xmpmeta>"
    prog = seeds["progressive_rgb_8x8.jpg"]
    seeds["progressive_rgb_8x8_metadata.jpg"] = prog[:2] + seg(0xE1, xmp) + seg(0xE2, b"ICC_PROFILE\0\x01\x01" +
                                                                                   bytes(128)) + \
        seg(0xED, b"Photoshop 3.0\x008BIM\x04\x04\0\0\0\0\0\x08\x1c\x02\x19\0\x04seed") + seg(0xFE, b"comment") + prog[2:]
    return seeds


def jpeg_regressions(baseline, progressive):
    """Inputs that once crashed or exhausted memory (texture_decode_oiio.cpp, prepareJpeg), kept as seeds."""
    # The Photoshop 8BIM resource and its IPTC dataset claim more bytes than the APP13 segment holds:
    # OpenImageIO 2.4 read 8 KiB past a heap buffer in JpgInput::open (decode_iptc_iim).
    iptc = bytearray(baseline)
    k = iptc.find(b"8BIM\x04\x04")
    assert k > 0, "the baseline seed has no IPTC block"
    iptc[k + 8:k + 12] = (0x4000).to_bytes(4, "big")
    j = iptc.find(b"\x1c\x02", k)
    iptc[j + 3:j + 5] = (0x2000).to_bytes(2, "big")
    # A progressive JPEG whose frame declares 52232 x 16392: libjpeg allocated GBs inside OpenImageIO's open(),
    # before any budget was checked.
    huge = bytearray(progressive)
    k = huge.find(b"\xff\xc2")
    huge[k + 5:k + 7] = (16392).to_bytes(2, "big")
    huge[k + 7:k + 9] = (52232).to_bytes(2, "big")
    return {"regression_iptc_overread.jpg": bytes(iptc), "regression_progressive_huge_frame.jpg": bytes(huge)}


# --- a synthesised glTF that reaches the material / texture / light / camera code


def textured_glb(image_png, uri_png):
    bin_ = b""
    views = []
    accessors = []

    def view(data, target=None):
        nonlocal bin_
        bin_ = pad4(bin_)
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data)})
        if target:
            views[-1]["target"] = target
        bin_ += data
        return len(views) - 1

    def accessor(fmt, values, ctype, atype, count, normalized=False, minmax=None, target=34962):
        v = view(struct.pack("<" + fmt * len(values), *values), target)
        a = {"bufferView": v, "componentType": ctype, "type": atype, "count": count}
        if normalized:
            a["normalized"] = True
        if minmax:
            a["min"], a["max"] = minmax
        accessors.append(a)
        return len(accessors) - 1

    pos = accessor("f", [0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0], 5126, "VEC3", 4, minmax=([0, 0, 0], [1, 1, 0]))
    nrm = accessor("f", [0, 0, 1] * 4, 5126, "VEC3", 4)
    uv0 = accessor("f", [0, 1, 1, 1, 1, 0, 0, 0], 5126, "VEC2", 4)
    uv1 = accessor("H", [0, 65535, 65535, 65535, 65535, 0, 0, 0], 5123, "VEC2", 4, normalized=True)
    col = accessor("B", [255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128], 5121, "VEC4", 4,
                   normalized=True)
    tan = accessor("f", [1, 0, 0, 1] * 4, 5126, "VEC4", 4)
    idx = accessor("H", [0, 1, 2, 0, 2, 3], 5123, "SCALAR", 6, target=34963)
    img_view = view(image_png)
    attributes = {"POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv0, "TEXCOORD_1": uv1, "COLOR_0": col,
                  "TANGENT": tan}
    tex0 = {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.3,
                                                                  "scale": [2, 2], "texCoord": 1}}}
    doc = {
        "asset": {"version": "2.0", "generator": "visbuf tests/fuzz/make_corpus.py"},
        "extensionsUsed": ["KHR_texture_transform", "KHR_materials_emissive_strength", "KHR_lights_punctual",
                           "KHR_mesh_quantization"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1, 0.5, 0.2], "intensity": 3, "range": 10},
            {"type": "spot", "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 3, 4]}],
        "nodes": [
            {"name": "root", "children": [1, 2], "translation": [1, 2, 3], "rotation": [0, 0.7071068, 0, 0.7071068],
             "scale": [2, 2, 2]},
            {"name": "quad", "mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -1, 1]},
            {"name": "mirrored", "mesh": 0, "scale": [-1, 1, 1]},
            {"name": "lamp", "translation": [0, 3, 0], "extensions": {"KHR_lights_punctual": {"light": 0}},
             "children": [5]},
            {"name": "eye", "camera": 0, "translation": [0, 0, 5]},
            {"name": "spot", "extensions": {"KHR_lights_punctual": {"light": 1}}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100}}],
        "meshes": [{"name": "quad", "primitives": [
            {"attributes": attributes, "indices": idx, "material": 0},
            {"attributes": {"POSITION": pos, "TEXCOORD_0": uv0}, "mode": 6, "material": 1},
        ]}],
        "materials": [
            {"name": "all-textures", "pbrMetallicRoughness": {
                "baseColorFactor": [1, 0.9, 0.8, 1], "baseColorTexture": tex0, "metallicFactor": 0.5,
                "roughnessFactor": 0.25, "metallicRoughnessTexture": {"index": 1}},
             "normalTexture": {"index": 1, "scale": 0.5}, "occlusionTexture": {"index": 0, "strength": 0.7},
             "emissiveTexture": {"index": 0, "texCoord": 1}, "emissiveFactor": [1, 1, 0],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
             "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True},
            {"name": "blend", "alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 1}],
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33648, "wrapT": 33071}, {}],
        "images": [{"name": "embedded", "bufferView": img_view, "mimeType": "image/png"},
                   {"name": "data-uri", "uri": "data:image/png;base64," + base64.b64encode(uri_png).decode()}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(pad4(bin_))}],
    }
    return glb(doc, bin_)


def rigid_gltf():
    """Rigid node animation: a triangle on a child node whose parent a LINEAR rotation and a STEP translation
    channel move (pack section "rigidObjects")."""
    data = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)                      # positions
    data += struct.pack("<2f", 0, 1)                                          # key times
    data += struct.pack("<8f", 0, 0, 0, 1, 0, 0.7071068, 0, 0.7071068)        # rotations
    data += struct.pack("<6f", 0, 0, 0, 1, 2, 3)                              # translations
    doc = {
        "asset": {"version": "2.0", "generator": "visbuf tests/fuzz/make_corpus.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "spinner", "children": [1], "scale": [2, 2, 2]},
                  {"name": "arm", "mesh": 0, "translation": [0.5, 0, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "animations": [{"name": "spin", "samplers": [{"input": 1, "output": 2},
                                                     {"input": 1, "output": 3, "interpolation": "STEP"}],
                        "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}},
                                     {"sampler": 1, "target": {"node": 0, "path": "translation"}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3,
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "type": "SCALAR", "count": 2, "min": [0], "max": [1]},
                      {"bufferView": 2, "componentType": 5126, "type": "VEC4", "count": 2},
                      {"bufferView": 3, "componentType": 5126, "type": "VEC3", "count": 2}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 8},
                        {"buffer": 0, "byteOffset": 44, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 76, "byteLength": 24}],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
    }
    return compact(doc)


def gltf_seeds(images):
    seeds = {
        "minimal.gltf": compact({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{}]}),
        "BoxMeshopt.glb": copy("BoxMeshopt/BoxMeshopt.glb"),
        "SparseMorphTargets.glb": copy("SparseMorphTargets/singleBlendshapeCube_sparse.glb"),
        "BoxWithInfinites.glb": copy("AssimpBadData/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb"),
        "SimpleSparseAccessor.gltf": embedded("SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf"),
        "SimpleMorph.gltf": embedded("SimpleMorph/glTF/SimpleMorph.gltf"),
        "AnimatedMorphCubeQuantized.glb": to_glb("AnimatedMorphCube/glTF-Quantized/AnimatedMorphCube.gltf"),
        "RiggedSimple.glb": to_glb("RiggedSimple/glTF/RiggedSimple.gltf"),
        "BoxInterleaved.glb": to_glb("BoxInterleaved/glTF/BoxInterleaved.gltf"),
        "TriangleStripIndexed.gltf": embedded("Mesh_PrimitiveMode/Mesh_PrimitiveMode/Mesh_PrimitiveMode_11.gltf"),
        "TriangleFan.gltf": embedded("Mesh_PrimitiveMode/Mesh_PrimitiveMode/Mesh_PrimitiveMode_05.gltf"),
        "Textured.glb": textured_glb(images["rgba8_2x2.png"], images["grey8_4x4_up.png"]),
        "RigidSpin.gltf": rigid_gltf(),
    }
    return seeds


def pack_seeds(visbuf, tmp):
    """Packs baked from glTF seeds already written to `tmp`."""
    seeds = {}
    for name, source, args in [("TriangleFan.vbp", "TriangleFan.gltf", []),
                               ("SimpleMorph.vbp", "SimpleMorph.gltf", ["--lod-count", "2"]),
                               ("RiggedSimple.vbp", "RiggedSimple.glb", ["--lod-count", "1"]),
                               ("Textured.vbp", "Textured.glb", ["--max-texture-size", "4"]),
                               # RGBA8 texels of 32^2 (5.4 KiB) from an in-repo asset: a zstd "texels" section
                               ("Textured_zstd.vbp", os.path.join(ROOT, "assets", "BoxTexturedNonPowerOfTwo", "glTF",
                                                                  "BoxTexturedNonPowerOfTwo.gltf"),
                                ["--max-texture-size", "32", "--textures", "rgba8", "--lod-count", "1"]),
                               ("RigidSpin.vbp", "RigidSpin.gltf", ["--lod-count", "1"]),
                               ("BoxInterleaved_quantized.vbp", "BoxInterleaved.glb", ["--quantize", "--lod-count", "2"])]:
        src = os.path.join(tmp, source)
        out = os.path.join(tmp, name)
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0")
        subprocess.run([visbuf, "bake", src, "-o", out] + args, check=True, env=env, stdout=subprocess.DEVNULL)
        with open(out, "rb") as f:
            seeds[name] = f.read()
    return seeds


def write(target, seeds):
    folder = os.path.join(CORPUS, target)
    os.makedirs(folder, exist_ok=True)
    for name, data in seeds.items():
        with open(os.path.join(folder, name), "wb") as f:
            f.write(data)
    print(f"{target}: {len(seeds)} seeds, {sum(map(len, seeds.values()))} bytes")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--visbuf", required=True, help="a built visbuf tool (for the pack seeds)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="visbuf-corpus-") as tmp:
        images = png_seeds()
        images.update(jpeg_seeds(tmp))
        gltf = gltf_seeds(images)
        for name, data in gltf.items():
            with open(os.path.join(tmp, name), "wb") as f:
                f.write(data)
        packs = pack_seeds(os.path.abspath(args.visbuf), tmp)
        write("fuzz_image_decode", images)
        write("fuzz_gltf_import", gltf)
        write("fuzz_pack_reader", packs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
