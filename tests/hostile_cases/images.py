"""Images (docs/security.md, "Budgets", image decode): PNG metadata that a recursive parser would choke on, in
every chunk that carries metadata and on every path an image takes into the bake (file, data: URI, buffer
view); the largest images the default pixel budget admits, in each PNG pixel format and bit depth and as
baseline and progressive JPEG, each within the peak memory docs/security.md states (checked here against the
same formula); two large images in one file (baked at once only within the in-flight budget); a JPEG with
megabytes of metadata; corrupt PNGs and JPEGs whose every line on stderr is visbuf's own.

Inputs are written at run time with zlib and struct only: constant images compress to a few hundred KB."""
import base64
import json
import os
import re
import struct
import zlib

MIB = 1 << 20
# docs/security.md: the bake of one image takes at most max(decode, 20 B/pixel) + 24 B per texel of the baked
# texture (S x S, S <= --max-texture-size, 2048 by default); JPEG decode adds OpenImageIO's 64 MiB buffer and,
# progressive, 2 B per pixel and component. The rest of the process (the program, the mesh, the pack being
# written) stays within BASELINE.
BASELINE = 192 * MIB
SIDE = 8192  # 8192 x 8192 = the default pixel budget, 64 Mpixel


def baked_side(width, height, max_size=2048):
    side = max(width, height)
    lower = 1 << (side.bit_length() - 1)
    nearest = lower * 2 if side * 2 >= lower * 3 else lower
    return min(nearest, max_size)


def peak_estimate(fmt, width, height, depth=8, components=3, progressive=False):
    pixels = width * height
    if fmt == "png":
        decode = pixels * (16 if depth == 16 else 4)
    else:
        decode = pixels * 4 + 64 * MIB
        if progressive:
            decode += ((width + 15) // 16 * 16) * ((height + 15) // 16 * 16) * 2 * components
    side = baked_side(width, height)
    return max(decode, 20 * pixels) + 24 * side * side


# --- PNG ---------------------------------------------------------------------------------------------------

def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


CHANNELS = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
ADAM7 = [(0, 0, 8, 8), (4, 0, 8, 8), (0, 4, 4, 8), (2, 0, 4, 4), (0, 2, 2, 4), (1, 0, 2, 2), (0, 1, 1, 2)]


def png_constant(width, height, colour_type, depth, pixel, interlaced=False, extra_before=(), extra_after=(),
                 plte=b"", trns=b""):
    """A PNG whose every pixel has the packed sample bytes `pixel` (8 and 16 bit; one byte of a packed row for
    lower depths). Rows are compressed as they are made: an 8192^2 16-bit image is 512 MiB raw, 0.5 MB here."""
    bytes_per_pixel = CHANNELS[colour_type] * depth / 8
    z = zlib.compressobj(6)
    parts = []
    passes = ADAM7 if interlaced else [(0, 0, 1, 1)]
    for x0, y0, dx, dy in passes:
        cols = (width - x0 + dx - 1) // dx if x0 < width else 0
        rows = (height - y0 + dy - 1) // dy if y0 < height else 0
        if cols == 0 or rows == 0:
            continue
        row_bytes = int(-(-cols * bytes_per_pixel // 1))
        row = b"\0" + (pixel * (row_bytes // len(pixel) + 1))[:row_bytes]
        block = row * 64
        for _ in range(rows // 64):
            parts.append(z.compress(block))
        parts.append(z.compress(row * (rows % 64)))
    parts.append(z.flush())
    ihdr = struct.pack(">IIBBBBB", width, height, depth, colour_type, 0, 0, 1 if interlaced else 0)
    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
    out += b"".join(chunk(k, d) for k, d in extra_before)
    if plte:
        out += chunk(b"PLTE", plte)
    if trns:
        out += chunk(b"tRNS", trns)
    out += chunk(b"IDAT", b"".join(parts))
    out += b"".join(chunk(k, d) for k, d in extra_after)
    return out + chunk(b"IEND", b"")


def nested_xmp(depth=20000):
    return (b"<x:xmpmeta xmlns:x='adobe:ns:meta/'><rdf:RDF>" + b"<rdf:li>" * depth + b"</rdf:li>" * depth +
            b"</rdf:RDF></x:xmpmeta>")


XMP_KEY = b"XML:com.adobe.xmp\0"


def metadata_variants():
    xmp = nested_xmp()
    tiff = b"MM\0*\0\0\0\x08" + struct.pack(">H", 20000) + b"".join(
        struct.pack(">HHII", 0x8769, 4, 1, 8) for _ in range(20000))  # Exif IFDs pointing at themselves
    return {
        "itxt": (b"iTXt", XMP_KEY + b"\0\0\0\0" + xmp),
        "itxt_compressed": (b"iTXt", XMP_KEY + b"\1\0\0\0" + zlib.compress(xmp, 9)),
        "ztxt": (b"zTXt", XMP_KEY + b"\0" + zlib.compress(xmp, 9)),
        "text": (b"tEXt", XMP_KEY + xmp),
        "text_exif": (b"tEXt", b"Raw profile type exif\0\nexif\n" + str(len(tiff)).encode() + b"\n" +
                      tiff.hex().encode()),
        "exif": (b"eXIf", tiff),
        "iccp": (b"iCCP", b"icc\0\0" + zlib.compress(b"\xff" * 4000000, 9)),
    }


# --- JPEG: constant images, encoded here (every block a DC difference of 0 and an end of block) ---------------

def jpeg_constant(width, height, components=3, progressive=False, segments=()):
    """A JPEG (4:4:4, 8-bit) of mid grey: one Huffman table of one 1-bit code (symbol 0: DC difference 0, and
    end of block / EOB run 0), so every block is 2 bits (baseline) or 1 bit per scan (progressive)."""
    def seg(marker, payload):
        return struct.pack(">BBH", 0xFF, marker, len(payload) + 2) + payload

    blocks = ((width + 7) // 8) * ((height + 7) // 8)

    def bits(count):  # `count` zero bits, padded with ones
        full, rest = divmod(count, 8)
        return b"\0" * full + (bytes([(1 << (8 - rest)) - 1]) if rest else b"")

    out = b"\xff\xd8" + seg(0xE0, b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0")
    out += b"".join(seg(m, p) for m, p in segments)
    out += seg(0xDB, b"\0" + b"\x01" * 64)
    frame = struct.pack(">BHHB", 8, height, width, components)
    frame += b"".join(struct.pack(">BBB", c + 1, 0x11, 0) for c in range(components))
    out += seg(0xC2 if progressive else 0xC0, frame)
    table = b"\x01" + b"\0" * 15 + b"\0"  # one code of length 1, symbol 0
    out += seg(0xC4, b"\x00" + table) + seg(0xC4, b"\x10" + table)
    if not progressive:
        sos = struct.pack(">B", components) + b"".join(struct.pack(">BB", c + 1, 0x00) for c in range(components))
        out += seg(0xDA, sos + b"\0\x3f\0") + bits(2 * components * blocks)
    else:
        sos = struct.pack(">B", components) + b"".join(struct.pack(">BB", c + 1, 0x00) for c in range(components))
        out += seg(0xDA, sos + b"\0\0\0") + bits(components * blocks)  # DC, all components
        for c in range(components):  # AC 1..63 of each component: EOB run 0 per block
            out += seg(0xDA, struct.pack(">BBB", 1, c + 1, 0x00) + b"\x01\x3f\0") + bits(blocks)
    return out + b"\xff\xd9"


# --- glTF --------------------------------------------------------------------------------------------------

TRIANGLE = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<6f", 0, 0, 1, 0, 0, 1)


def gltf(images, embedded=()):
    """A triangle whose materials use `images` (glTF image objects) as base colour textures; `embedded`: bytes
    appended to the buffer, each with a buffer view (image i uses view 2 + i when it says "bufferView")."""
    blob = TRIANGLE
    views = [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}]
    for data in embedded:
        while len(blob) % 4:
            blob += b"\0"
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob += data
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": list(range(len(images)))}],
        "nodes": [{"mesh": i} for i in range(len(images))],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": i}]}
                   for i in range(len(images))],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0],
                       "max": [1, 1, 0]}, {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
        "images": images, "textures": [{"source": i} for i in range(len(images))],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}} for i in range(len(images))],
    }
    return json.dumps(doc).encode()


def cases(ctx):
    def bake(case, files, doc, extra=()):
        root = ctx.folder(case)
        for name, data in files.items():
            with open(os.path.join(root, name), "wb") as f:
                f.write(data)
        with open(os.path.join(root, "scene.gltf"), "wb") as f:
            f.write(doc)
        out = os.path.join(root, "out.vbp")
        return ctx.visbuf_run(["bake", "scene.gltf", "-o", out, *extra], root), out

    def only_visbuf_lines(outcome):
        # visbuf's lines: errors and warnings ("visbuf bake: ..."), progress ("bake: ...").
        stray = [line for line in outcome.text.splitlines()
                 if line.strip() and not line.startswith(("visbuf ", "bake: "))]
        return f"stderr lines without visbuf's prefix: {stray[:3]}" if stray else None

    def baked_within(case, outcome, out, bound):
        def check():
            if not os.path.exists(out):
                return "no pack written"
            if outcome.rss_kib * 1024 > bound:
                return f"peak RSS {outcome.rss_kib // 1024} MiB over the documented {bound // MIB} MiB"
            return only_visbuf_lines(outcome)
        if ctx.expect_ok(case, outcome, check):
            print(f"     {case}: {outcome.seconds:.1f} s, peak {outcome.rss_kib // 1024} MiB "
                  f"(documented bound {bound // MIB} MiB)", flush=True)

    # Metadata in every chunk kind that carries it, on a small image: baked, pixels as without (unit tests
    # compare them); each variant as a file; the iTXt one also as a data: URI and in a buffer view.
    for name, (kind, data) in metadata_variants().items():
        def run(case=f"png_metadata_{name}", kind=kind, data=data):
            png = png_constant(64, 64, 6, 8, b"\x10\x80\xf0\xff", extra_before=[(kind, data)],
                               extra_after=[(kind, data)])
            outcome, out = bake(case, {"m.png": png}, gltf([{"uri": "m.png"}]))
            baked_within(case, outcome, out, BASELINE + peak_estimate("png", 64, 64) + 2 * len(png))
        yield f"png_metadata_{name}", run
    xmp_chunk = metadata_variants()["itxt"]
    xmp_png = png_constant(64, 64, 6, 8, b"\x10\x80\xf0\xff", extra_before=[xmp_chunk])

    def data_uri():
        uri = "data:image/png;base64," + base64.b64encode(xmp_png).decode()
        outcome, out = bake("png_metadata_data_uri", {}, gltf([{"uri": uri}]))
        baked_within("png_metadata_data_uri", outcome, out, BASELINE + 8 * len(xmp_png))
    yield "png_metadata_data_uri", data_uri

    def buffer_view():
        outcome, out = bake("png_metadata_buffer_view", {},
                            gltf([{"bufferView": 2, "mimeType": "image/png"}], embedded=[xmp_png]))
        baked_within("png_metadata_buffer_view", outcome, out, BASELINE + 8 * len(xmp_png))
    yield "png_metadata_buffer_view", buffer_view

    # The budget's edge, 8192 x 8192, on each decode path: 16-bit to float (RGBA, Adam7, grey), 8-bit to codes
    # (RGBA, Adam7 RGB, 1-bit grey, palette with tRNS); the unit tests cover every colour type and depth.
    edge = {
        "png_rgba16": dict(colour_type=6, depth=16, pixel=b"\x12\x34\x56\x78\x9a\xbc\xff\xff"),
        "png_rgba16_adam7": dict(colour_type=6, depth=16, pixel=b"\x12\x34\x56\x78\x9a\xbc\xff\xff",
                                 interlaced=True),
        "png_grey16": dict(colour_type=0, depth=16, pixel=b"\x80\x00"),
        "png_rgba8": dict(colour_type=6, depth=8, pixel=b"\x10\x80\xf0\xff"),
        "png_rgb8_adam7": dict(colour_type=2, depth=8, pixel=b"\x10\x80\xf0", interlaced=True),
        "png_grey1": dict(colour_type=0, depth=1, pixel=b"\xaa"),
        "png_palette8_trns": dict(colour_type=3, depth=8, pixel=b"\x01", plte=b"\0\0\0\xff\x80\x00",
                                  trns=b"\xff\x80"),
    }
    for name, kw in edge.items():
        def run(case=f"edge_{name}", kw=kw):
            png = png_constant(SIDE, SIDE, **kw)
            outcome, out = bake(case, {"big.png": png}, gltf([{"uri": "big.png"}]))
            baked_within(case, outcome, out, BASELINE + len(png) + peak_estimate("png", SIDE, SIDE, kw["depth"]))
        yield f"edge_{name}", run

    # Non-square at the budget (8192 x 8191: resampled in float), 16-bit: the largest decode plus the resize.
    def non_square():
        png = png_constant(SIDE, SIDE - 1, 6, 16, b"\x12\x34\x56\x78\x9a\xbc\xff\xff")
        outcome, out = bake("edge_png_rgba16_non_square", {"big.png": png}, gltf([{"uri": "big.png"}]))
        baked_within("edge_png_rgba16_non_square", outcome, out,
                     BASELINE + len(png) + peak_estimate("png", SIDE, SIDE - 1, 16))
    yield "edge_png_rgba16_non_square", non_square

    for name, kw in {"jpeg_baseline_rgb": dict(components=3), "jpeg_progressive_rgb": dict(progressive=True),
                     "jpeg_progressive_grey": dict(components=1, progressive=True)}.items():
        def run(case=f"edge_{name}", kw=kw):
            jpg = jpeg_constant(SIDE, SIDE, **kw)
            outcome, out = bake(case, {"big.jpg": jpg}, gltf([{"uri": "big.jpg"}]))
            baked_within(case, outcome, out, BASELINE + len(jpg) + peak_estimate("jpeg", SIDE, SIDE, **kw))
        yield f"edge_{name}", run

    # Two 6144 x 6144 8-bit images (resampled in float: 20 B/pixel, each estimate over half the in-flight
    # budget of 1.5 GiB) in one file: baked one at a time, so the peak is one image's, not two.
    def two_large():
        png = png_constant(6144, 6144, 6, 8, b"\x10\x80\xf0\xff")
        files = {f"big{i}.png": png for i in range(2)}
        outcome, out = bake("two_large_png8", files, gltf([{"uri": f"big{i}.png"} for i in range(2)]))
        baked_within("two_large_png8", outcome, out, BASELINE + 2 * len(png) + peak_estimate("png", 6144, 6144, 8))
    yield "two_large_png8", two_large

    # A JPEG with 16 MB of metadata: 256 full APP1 (XMP, Exif), APP2 (ICC), APP13 (IPTC) and COM segments.
    def jpeg_metadata():
        xmp = b"http://ns.adobe.com/xap/1.0/\0" + nested_xmp(7000)[:65000]
        segments = []
        for i in range(64):
            segments += [(0xE1, xmp), (0xE1, b"Exif\0\0MM\0*\0\0\0\x08\xff\xff" + b"\0" * 65000),
                         (0xE2, b"ICC_PROFILE\0\x01\x01" + b"\xff" * 65000),
                         (0xED, b"Photoshop 3.0\x008BIM\x04\x04\0\0\x7f\xff\xff\xff" + b"\0" * 65000),
                         (0xFE, b"c" * 65000)]
        jpg = jpeg_constant(512, 512, segments=segments[:256])
        outcome, out = bake("jpeg_huge_metadata", {"m.jpg": jpg}, gltf([{"uri": "m.jpg"}]))
        baked_within("jpeg_huge_metadata", outcome, out, BASELINE + 3 * len(jpg) + peak_estimate("jpeg", 512, 512))
    yield "jpeg_huge_metadata", jpeg_metadata

    # Corrupt images: with --strict-images a clean error naming the image; by default the texture is dropped with a
    # warning naming the image and the bake succeeds. Either way nothing on stderr but visbuf's own lines.
    good = png_constant(256, 256, 6, 8, b"\x10\x80\xf0\xff")
    idat = good.index(b"IDAT")
    corrupt = {
        "png_idat_crc": good[:idat + 10] + bytes([good[idat + 10] ^ 0xFF]) + good[idat + 11:],
        "png_truncated": good[:len(good) // 2],
        "png_bad_zlib": good[:idat + 6] + b"\xde\xad\xbe\xef" * 4 + good[idat + 22:],
        "png_bad_ihdr": good[:24] + b"\x03" + good[25:],
        "png_no_idat": good[:idat - 4] + chunk(b"IEND", b""),
        "jpeg_truncated": jpeg_constant(256, 256)[:300],
    }
    for name, data in corrupt.items():
        def run(case=f"corrupt_{name}", data=data):
            file = "bad.jpg" if "jpeg" in case else "bad.png"
            outcome, out = bake(case, {file: data}, gltf([{"uri": file}]), ("--strict-images",))
            if ctx.expect_error(case, outcome, r"image 0 'bad\.(png|jpg)': "):
                problem = only_visbuf_lines(outcome) or ("a pack was written" if os.path.exists(out) else None)
                if problem:
                    ctx.fail(case, problem, outcome)
            outcome, out = bake(case + "_dropped", {file: data}, gltf([{"uri": file}]))

            def dropped_with_warning():
                if not re.search(r"warning: .*image 0 'bad\.(png|jpg)': .*; its texture is dropped from the "
                                 r"materials that use it", outcome.text):
                    return "no warning naming the dropped image"
                return only_visbuf_lines(outcome)
            ctx.expect_ok(case + "_dropped", outcome, dropped_with_warning)
        yield f"corrupt_{name}", run
