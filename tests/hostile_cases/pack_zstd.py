"""Hostile zstd sections in packs (docs/pack-format.md, "Section encodings"): a baked pack's compressed "texels"
section rewritten -- truncated, lying about its size, a skippable or dictionary frame, a damaged frame checksum, a
decompression bomb -- and loaded by `render`: each a clean error (exit 1) naming the section and the problem,
within the runner's time and memory caps. (That the honest compressed pack renders the image of its raw twin is
tests/cli_bake.cmake's.)
"""
import importlib.util
import os
import struct
import zlib

ENTRY = struct.Struct("<16sQQQIIQII")  # SectionEntry, 64 bytes
HEADER = struct.Struct("<4sIIIIIQ7II")  # Header, 64 bytes


def _scene_writer():
    """write_scene of the sibling module io.py (loaded by path: the name shadows the standard library's io)."""
    spec = importlib.util.spec_from_file_location("hostile_io", os.path.join(os.path.dirname(__file__), "io.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.write_scene


def read_pack(data):
    """(header fields, [[name, decoded size, count, elementSize, encoding, stored bytes], ...]) in file order."""
    h = list(HEADER.unpack_from(data, 0))
    sections = []
    for i in range(h[4]):
        name, off, size, count, esize, _crc, stored, enc, _res = ENTRY.unpack_from(data, 64 + 64 * i)
        sections.append([name, size, count, esize, enc, data[off:off + stored]])
    return h, sections


def write_pack(h, sections):
    """Lays the sections out afresh (16-aligned), with correct CRCs: edits reach the reader's later checks."""
    table_end = 64 + 64 * len(sections)
    cursor = (table_end + 15) // 16 * 16
    entries, body = [], bytearray(cursor - table_end)
    for name, size, count, esize, enc, stored in sections:
        entries.append(ENTRY.pack(name, cursor, size, count, esize, zlib.crc32(stored), len(stored), enc, 0))
        padded = (len(stored) + 15) // 16 * 16
        body += stored + bytes(padded - len(stored))
        cursor += padded
    h = list(h)
    h[4], h[6], h[-1] = len(sections), cursor, 0
    table = b"".join(entries)
    h[-1] = zlib.crc32(table, zlib.crc32(HEADER.pack(*h)))
    return HEADER.pack(*h) + table + bytes(body)


def frames_of(stored):
    """(chunkBytes, [frame bytes]) of a zstd section's stored bytes."""
    chunk, count, _ = struct.unpack_from("<IIQ", stored, 0)
    sizes = struct.unpack_from(f"<{count}I", stored, 16)
    at, frames = 16 + 4 * count, []
    for n in sizes:
        frames.append(stored[at:at + n])
        at += n
    return chunk, frames


def stored_of(chunk, frames, frame_count=None):
    count = len(frames) if frame_count is None else frame_count
    return (struct.pack("<IIQ", chunk, count, 0) + struct.pack(f"<{len(frames)}I", *map(len, frames)) +
            b"".join(frames))


def cases(ctx):
    write_scene = _scene_writer()

    source = {}

    def baked(case):
        """The textured scene baked once (its 256^2 image gives a compressible "texels" section of several KiB):
        a fresh folder for the case and the pack's parsed header and sections."""
        if "data" not in source:
            root = ctx.folder("zstd_source")
            write_scene(root, image_size=256)
            outcome = ctx.visbuf_run(["bake", "scene.gltf", "-o", "z.vbp"], root)
            if outcome.code != 0:
                ctx.fail(case, "bake failed", outcome)
                return None, None
            with open(os.path.join(root, "z.vbp"), "rb") as f:
                source["data"] = f.read()
        h, sections = read_pack(source["data"])
        texels = next((s for s in sections if s[0].rstrip(b"\0") == b"texels"), None)
        if texels is None or texels[4] != 1:
            ctx.fail(case, "the baked pack's texels section is not zstd-compressed")
            return None, None
        return ctx.folder(case), (h, sections, texels)

    def hostile(case, edit, pattern, extra=()):
        def run():
            root, pack = baked(case)
            if root is None:
                return
            h, sections, texels = pack
            edit(texels)
            with open(os.path.join(root, "bad.vbp"), "wb") as f:
                f.write(write_pack(h, sections))
            outcome = ctx.visbuf_run(["render", "--scene", "bad.vbp", "--size", "32x32", *extra, "-o", "out.png"],
                                     root)
            ctx.expect_error(case, outcome, pattern)
        return run

    def rewrite_frames(change):
        def edit(texels):
            chunk, frames = frames_of(texels[5])
            texels[5] = stored_of(chunk, change(frames))
        return edit

    def lying_size(delta):
        def edit(texels):
            texels[1] += delta
            texels[2] += delta
        return edit

    def bomb(size):
        def edit(texels):
            texels[1] = texels[2] = size
        return edit

    def dictionary(frames):
        f = bytearray(frames[0])
        f[4] |= 0x01
        return [bytes(f)] + frames[1:]

    def bad_checksum(frames):
        f = bytearray(frames[0])
        f[-1] ^= 0x5A
        return [bytes(f)] + frames[1:]

    skippable = struct.pack("<II", 0x184D2A50, 4) + b"junk"
    yield "zstd_truncated_frame", hostile("zstd_truncated_frame",
                                          rewrite_frames(lambda fr: [fr[0][:-1]] + fr[1:]),
                                          r"section 'texels': zstd frame 0 .*truncated or damaged")
    yield "zstd_trailing_bytes", hostile("zstd_trailing_bytes",
                                         rewrite_frames(lambda fr: [fr[0] + b"\0\0\0"] + fr[1:]),
                                         r"section 'texels': zstd frame 0 .*trailing bytes")
    yield "zstd_skippable_frame", hostile("zstd_skippable_frame",
                                          rewrite_frames(lambda fr: [skippable + fr[0]] + fr[1:]),
                                          r"section 'texels': zstd frame 0 .*skippable frame")
    yield "zstd_dictionary_frame", hostile("zstd_dictionary_frame", rewrite_frames(dictionary),
                                           r"section 'texels': zstd frame 0 .*dictionary")
    yield "zstd_damaged_checksum", hostile("zstd_damaged_checksum", rewrite_frames(bad_checksum),
                                           r"section 'texels' \(class \d+\): zstd frame 0: .*checksum")
    yield "zstd_size_larger", hostile("zstd_size_larger", lying_size(16),
                                      r"section 'texels': zstd frame \d+ .*declares \d+ decoded bytes")
    yield "zstd_size_smaller", hostile("zstd_size_smaller", lying_size(-16),
                                       r"section 'texels': zstd frame \d+ .*declares \d+ decoded bytes")
    yield "zstd_bomb_1TiB", hostile("zstd_bomb_1TiB", bomb(1 << 40), r"more than the reader's budget")
    yield "zstd_bomb_within_budget", hostile("zstd_bomb_within_budget", bomb(3 << 30),
                                             r"section 'texels': zstd: field 'frameCount'")
    yield "zstd_budget_option", hostile("zstd_budget_option", bomb(2 << 20),
                                        r"more than the reader's budget of 1048576 bytes.*--max-import-memory",
                                        extra=("--max-import-memory", "1048576"))
