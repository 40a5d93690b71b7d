"""Outputs aimed at inputs, packs changed under a running render, and the terminal: every case is generated here.

- Every output of a command (-o, --json, --ids-out, bench's folder files) aimed at one of its inputs -- the glTF,
  its buffer, its image, a pack, a --mesh file, directly, through a hard link or a symbolic link -- is refused
  with exit 1 and a message naming it, and the input's bytes are unchanged (hashes before and after); two outputs
  of one command in one file are refused too.
- A pack truncated or overwritten in place while `render` loads and renders it: a clean error or the correct
  image (the one rendered from the untouched pack), never a signal.
- Text typed on the command line is echoed with control characters escaped; empty paths, misspelt subcommands
  and a pack given to --mesh get messages that say so.
"""
import hashlib
import json
import os
import random
import re
import struct
import subprocess
import threading
import time
import zlib

ESCAPE = "\x1b[31m"


def png(width, height, seed=1):
    """An RGBA8 PNG of a deterministic pattern."""
    rows = []
    for y in range(height):
        row = bytearray([0])
        for x in range(width):
            row += bytes([(x * 7 + seed) & 255, (y * 5 + seed) & 255, ((x ^ y) * 3) & 255, 255])
        rows.append(bytes(row))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(b"".join(rows), 6)) + chunk(b"IEND", b""))


def write_scene(root, name="scene", grid=24, image_size=64):
    """A textured grid (grid x grid quads) with an external buffer `name`.bin and image `name`.png."""
    positions, uvs, indices = bytearray(), bytearray(), bytearray()
    n = grid + 1
    for j in range(n):
        for i in range(n):
            positions += struct.pack("<3f", i / grid, j / grid, 0.0)
            uvs += struct.pack("<2f", i / grid, j / grid)
    for j in range(grid):
        for i in range(grid):
            a = j * n + i
            indices += struct.pack("<6I", a, a + 1, a + n, a + 1, a + n + 1, a + n)
    data = bytes(positions + uvs + indices)
    count = n * n
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"uri": name + ".bin", "byteLength": len(data)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
                        {"buffer": 0, "byteOffset": len(positions), "byteLength": len(uvs)},
                        {"buffer": 0, "byteOffset": len(positions) + len(uvs), "byteLength": len(indices)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": count, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5125, "count": grid * grid * 6, "type": "SCALAR"}],
        "images": [{"uri": name + ".png"}],
        "textures": [{"source": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0,
    }
    with open(os.path.join(root, name + ".bin"), "wb") as f:
        f.write(data)
    with open(os.path.join(root, name + ".png"), "wb") as f:
        f.write(png(image_size, image_size))
    path = os.path.join(root, name + ".gltf")
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def digest(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def hashes(root):
    """Every regular file's hash under root (links not followed)."""
    out = {}
    for name in sorted(os.listdir(root)):
        p = os.path.join(root, name)
        if os.path.isfile(p) and not os.path.islink(p):
            out[name] = digest(p)
    return out


def expect_usage(ctx, case, outcome, pattern):
    """A usage error: exit 2 and stderr matching `pattern`, within the caps."""
    ctx.count += 1
    if not ctx._capped(case, outcome):
        return False
    if outcome.code != 2:
        ctx.fail(case, f"exit code {outcome.code}, expected 2", outcome)
        return False
    if not re.search(pattern, outcome.text):
        ctx.fail(case, f"stderr does not match /{pattern}/", outcome)
        return False
    print(f"ok   {case}: exit 2 in {outcome.seconds:.2f} s: {outcome.text.strip().splitlines()[0][:160]}", flush=True)
    return True


def no_raw_controls(ctx, case, outcome):
    """Nothing printed holds a raw control character other than newline (and the tab of help text)."""
    for stream, data in (("stderr", outcome.stderr), ("stdout", outcome.stdout)):
        bad = [b for b in data if (b < 0x20 and b not in (0x0A, 0x09)) or b == 0x7F]
        if bad:
            ctx.fail(case, f"{stream} holds raw control bytes {sorted(set(bad))}", outcome)
            return False
    return True


def cases(ctx):
    # ---- outputs aimed at inputs -------------------------------------------------------------------------------
    def refused(case, root, args, pattern, before=None):
        before = before or hashes(root)
        outcome = ctx.visbuf_run(args, root)
        if ctx.expect_error(case, outcome, pattern):
            after = hashes(root)
            changed = [k for k in before if after.get(k) != before[k]]
            if changed:
                ctx.fail(case, f"input bytes changed: {changed}", outcome)
            stray = [k for k in os.listdir(root) if ".tmp" in k]
            if stray:
                ctx.fail(case, f"temporary files left: {stray}", outcome)

    def bake_over(case, output_name, extra=(), link=None, pattern=None):
        def run():
            root = ctx.folder(case)
            write_scene(root)
            target = output_name
            if link == "hard":
                os.link(os.path.join(root, output_name), os.path.join(root, "hard.out"))
                target = "hard.out"
            elif link == "symlink":
                os.symlink(output_name, os.path.join(root, "soft.out"))
                target = "soft.out"
            refused(case, root, ["bake", "scene.gltf", *extra, "-o", target] if "--json" not in extra else
                    ["bake", "scene.gltf", "-o", "fresh.vbp", *extra, target],
                    pattern or rf"{re.escape(target)}'?: is an input of this command")
        return run

    for kind, name, role in (("buffer", "scene.bin", r"buffer 0"), ("image", "scene.png", r"image 0"),
                             ("gltf", "scene.gltf", r"")):
        yield f"bake_o_over_{kind}", bake_over(f"bake_o_over_{kind}", name, pattern=rf"is an input of this command.*{role}")
        yield f"bake_json_over_{kind}", bake_over(f"bake_json_over_{kind}", name, extra=("--json",))
        yield f"bake_o_hardlink_{kind}", bake_over(f"bake_o_hardlink_{kind}", name, link="hard")
        yield f"bake_o_symlink_{kind}", bake_over(f"bake_o_symlink_{kind}", name, link="symlink")
    yield "bake_no_textures_o_over_image", bake_over("bake_no_textures_o_over_image", "scene.png",
                                                     extra=("--no-textures",))

    def two_outputs(case, args):
        def run():
            root = ctx.folder(case)
            write_scene(root)
            refused(case, root, args, r"is the same file as")
        return run

    yield "bake_o_and_json_same_file", two_outputs("bake_o_and_json_same_file",
                                                   ["bake", "scene.gltf", "-o", "x.vbp", "--json", "./x.vbp"])
    yield "render_o_and_json_same_file", two_outputs("render_o_and_json_same_file",
                                                     ["render", "--scene", "field", "-o", "x.png", "--json", "x.png"])

    def render_over_pack(case, option, link=None):
        def run():
            root = ctx.folder(case)
            write_scene(root)
            bake = ctx.visbuf_run(["bake", "scene.gltf", "-o", "p.vbp"], root)
            if bake.code != 0:
                return ctx.fail(case, "could not bake the pack", bake)
            target = "p.vbp"
            if link == "symlink":
                os.symlink("p.vbp", os.path.join(root, "p.png"))
                target = "p.png"
            elif link == "hard":
                os.link(os.path.join(root, "p.vbp"), os.path.join(root, "p.tif"))
                target = "p.tif"
            refused(case, root, ["render", "--scene", "p.vbp", "--device", "cpu", option, target],
                    rf"{re.escape(option)} '{re.escape(target)}': is an input of this command")
        return run

    yield "render_json_over_pack", render_over_pack("render_json_over_pack", "--json")
    yield "render_o_symlink_pack", render_over_pack("render_o_symlink_pack", "-o", link="symlink")
    yield "render_ids_hardlink_pack", render_over_pack("render_ids_hardlink_pack", "--ids-out", link="hard")

    def render_over_referenced(case, args, pattern):
        def run():
            root = ctx.folder(case)
            write_scene(root)
            refused(case, root, args, pattern)
        return run

    # Known only once the glTF is read: its buffer and image, the --mesh file's buffer.
    yield "render_json_over_gltf_buffer", render_over_referenced(
        "render_json_over_gltf_buffer", ["render", "--scene", "scene.gltf", "--device", "cpu", "--size", "32x32",
                                         "--json", "scene.bin"], r"--json 'scene.bin': is an input .*buffer 0")
    yield "render_o_over_gltf_image", render_over_referenced(
        "render_o_over_gltf_image", ["render", "--scene", "scene.gltf", "--device", "cpu", "--size", "32x32",
                                     "-o", "scene.png"], r"-o 'scene.png': is an input .*image 0")
    yield "render_json_over_mesh", render_over_referenced(
        "render_json_over_mesh", ["render", "--mesh", "scene.gltf", "--objects", "4", "--device", "cpu", "--size",
                                  "32x32", "--json", "scene.gltf"], r"--json 'scene.gltf': is an input")
    yield "render_json_over_mesh_buffer", render_over_referenced(
        "render_json_over_mesh_buffer", ["render", "--mesh", "scene.gltf", "--objects", "4", "--device", "cpu",
                                         "--size", "32x32", "--json", "scene.bin"], r"--json 'scene.bin': is an input")

    def bench_folder_over_scene(case):
        def run():
            root = ctx.folder(case)
            os.makedirs(os.path.join(root, "out"))
            path = write_scene(root)
            os.rename(path, os.path.join(root, "out", "bench.json"))
            os.rename(os.path.join(root, "scene.bin"), os.path.join(root, "out", "scene.bin"))
            os.rename(os.path.join(root, "scene.png"), os.path.join(root, "out", "scene.png"))
            before = hashes(os.path.join(root, "out"))
            outcome = ctx.visbuf_run(["bench", "--scene", "out/bench.json", "--device", "cpu", "-o", "out"], root)
            if ctx.expect_error(case, outcome, r"out/bench\.json'?: is an input of this command"):
                if hashes(os.path.join(root, "out")) != before:
                    ctx.fail(case, "input bytes changed", outcome)
        return run

    yield "bench_folder_file_over_scene", bench_folder_over_scene("bench_folder_file_over_scene")

    # ---- packs changed while a render reads them ---------------------------------------------------------------
    def changing_pack(case, mode):
        def run():
            root = ctx.folder(case)
            write_scene(root, grid=64, image_size=512)
            bake = ctx.visbuf_run(["bake", "scene.gltf", "--textures", "rgba8", "-o", "p.vbp"], root)
            if bake.code != 0:
                return ctx.fail(case, "could not bake the pack", bake)
            pack = os.path.join(root, "p.vbp")
            with open(pack, "rb") as f:
                original = f.read()
            render = ["render", "--scene", "p.vbp", "--device", "cpu", "--size", "48x48", "--frames", "3"]
            reference = ctx.visbuf_run(render + ["-o", "ref.png"], root)
            if reference.code != 0:
                return ctx.fail(case, "the untouched pack does not render", reference)
            ref = digest(os.path.join(root, "ref.png"))
            # The writer changes the file in place, again and again, while each render runs: the load reads a
            # damaged file, a file that changes under it, or a restored one. Several renders, each started at once.
            rng = random.Random(47)
            for attempt in range(3):
                stop = threading.Event()

                def writer():
                    fd = os.open(pack, os.O_WRONLY)
                    try:
                        k = 1
                        while not stop.is_set():
                            if mode == "truncate":
                                os.ftruncate(fd, len(original) * k // 8)
                                k = k % 7 + 1
                            else:
                                at = len(original) * k // 8
                                os.pwrite(fd, bytes(b ^ 0x5A for b in original[at:at + 4096]), at)
                                k = k % 7 + 1
                            # Each state held for 0..20 ms: a load may read a damaged file that holds still (the
                            # checksums or sizes refuse it), one that changes under it, or the restored one.
                            time.sleep(rng.uniform(0.0, 0.02))
                            os.pwrite(fd, original, 0)
                            time.sleep(rng.uniform(0.0, 0.02))
                    finally:
                        os.pwrite(fd, original, 0)
                        os.ftruncate(fd, len(original))
                        os.close(fd)

                thread = threading.Thread(target=writer)
                thread.start()
                try:
                    out = f"run{attempt}.png"
                    outcome = ctx.visbuf_run(render + ["-o", out], root)
                finally:
                    stop.set()
                    thread.join()
                name = f"{case}#{attempt}"
                if outcome.code == 0:
                    ctx.expect_ok(name, outcome, lambda: None if digest(os.path.join(root, out)) == ref else
                                  "rendered an image that differs from the untouched pack's")
                else:
                    ctx.expect_error(name, outcome, r"p\.vbp: .*(changed while|shrank|checksum|truncated|"
                                                    r"runs past|fileSize|smaller than)")
        return run

    yield "pack_truncated_during_render", changing_pack("pack_truncated_during_render", "truncate")
    yield "pack_overwritten_during_render", changing_pack("pack_overwritten_during_render", "overwrite")

    # ---- the terminal and messages -----------------------------------------------------------------------------
    def usage_case(case, args, pattern, exit_code=2):
        def run():
            root = ctx.folder(case)
            outcome = ctx.visbuf_run(args, root)
            ok = (expect_usage(ctx, case, outcome, pattern) if exit_code == 2 else
                  ctx.expect_error(case, outcome, pattern))
            if ok:
                no_raw_controls(ctx, case, outcome)
        return run

    yield "escape_in_unknown_option", usage_case("escape_in_unknown_option", ["render", "--" + ESCAPE + "red"],
                                                 r"\\x1b\[31mred")
    yield "escape_in_option_value", usage_case("escape_in_option_value", ["render", "--path", ESCAPE + "x"],
                                               r"--path.*\\x1b\[31mx", exit_code=1)
    yield "escape_in_bake_input", usage_case("escape_in_bake_input", ["bake", ESCAPE + ".gltf", "-o", "o.vbp"],
                                             r"\\x1b\[31m\.gltf", exit_code=1)
    yield "escape_in_scene_path", usage_case("escape_in_scene_path",
                                             ["render", "--scene", "\x1b]0;title\x07.vbp", "--device", "cpu"],
                                             r"\\x1b\]0;title\\x07\.vbp", exit_code=1)
    yield "escape_as_subcommand", usage_case("escape_as_subcommand", ["\x1b[2J"], r"unknown subcommand '\\x1b\[2J'")
    yield "escape_in_extra_argument", usage_case("escape_in_extra_argument",
                                                 ["render", "x\x9b31m", "--device", "cpu"], r"x\\xc2\\x9b31m|x\\x9b31m")
    yield "misspelt_subcommand", usage_case("misspelt_subcommand", ["rendr"],
                                            r"unknown subcommand 'rendr' \(did you mean render\?\).*bake")
    yield "misspelt_subcommand_bake", usage_case("misspelt_subcommand_bake", ["bkae"],
                                                 r"unknown subcommand 'bkae' \(did you mean bake\?\)")
    yield "no_subcommand", usage_case("no_subcommand", [], r"a subcommand is required: render, bake")
    for option in ("--scene", "--mesh", "--json", "--ids-out"):
        yield f"render_empty{option}", usage_case(f"render_empty{option}", ["render", option, ""],
                                                  rf"{option}: empty path", exit_code=1)
    yield "bake_empty_input", usage_case("bake_empty_input", ["bake", "", "-o", "x.vbp"], r"input: empty path",
                                         exit_code=1)
    yield "bake_empty_output", usage_case("bake_empty_output", ["bake", "a.gltf", "-o", ""], r"-o.*: empty path",
                                          exit_code=1)
    yield "bench_empty_mesh", usage_case("bench_empty_mesh", ["bench", "--mesh", ""], r"--mesh: empty path",
                                         exit_code=1)

    def mesh_is_pack(case):
        def run():
            root = ctx.folder(case)
            write_scene(root)
            bake = ctx.visbuf_run(["bake", "scene.gltf", "-o", "Fox.vbp"], root)
            if bake.code != 0:
                return ctx.fail(case, "could not bake the pack", bake)
            outcome = ctx.visbuf_run(["render", "--mesh", "Fox.vbp", "--device", "cpu", "--size", "32x32"], root)
            ctx.expect_error(case, outcome, r"--mesh 'Fox\.vbp': is a visbuf pack; --mesh takes a \.gltf/\.glb")
        return run

    yield "render_mesh_is_pack", mesh_is_pack("render_mesh_is_pack")
