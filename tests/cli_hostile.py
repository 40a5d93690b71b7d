#!/usr/bin/env python3
"""The hostile-file suite (docs/security.md): `visbuf bake FILE -o OUT` (and `visbuf render --scene`
for a FIFO) on each file of tests/data/hostile, asserting for every case:

  - exit code 1 (not a crash: no signal, no 134), and a message on stderr naming the problem;
  - it finishes within 10 s and its peak RSS stays under 1 GiB;
  - no byte of a canary file placed OUTSIDE the asset's folder appears in any output (stdout, stderr, the
    pack, any file left in the output folder), and no pack is left behind.

Traversal cases (plain, percent-encoded, absolute, through a symlinked file and a symlinked folder; for a
buffer and for an image) are run three times: with the canary present, with a canary of another size, and
with no canary at all; the three messages must be byte-identical (so the error tells nothing about what is
outside, not even its size). Each is also run once with --allow-uri-root naming the canary's folder, as a
positive control: the bake then succeeds and the canary's bytes DO reach the pack, which shows that the
check above would catch a leak.

Usage: cli_hostile.py --visbuf build/tools/visbuf [--data tests/data/hostile] [--work DIR] [-k SUBSTRING]
"""
import argparse
import ctypes
import ctypes.util
import os
import re
import shutil
import struct
import sys
import tempfile
import time
import zlib
import subprocess

TIME_LIMIT_S = 10.0
RSS_LIMIT_KIB = 1024 * 1024  # 1 GiB

CANARY = b"S3cr3t!Bytes"  # 12 bytes = the hostile files' byteLength: if read, it would import cleanly
CANARY_OTHER_SIZE = b"S3cr3t!Bytes, but 100 bytes long this time " + b"x" * 57

# A 4x4 RGBA PNG outside the folder; as a normal map (linear) it would be baked texel for texel.
CANARY_TEXELS = bytes((i * 37 + 11) & 0xFF for i in range(64))


def png_rgba(width, height, rgba):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    rows = b"".join(b"\x00" + rgba[y * width * 4:(y + 1) * width * 4] for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


CANARY_PNG = png_rgba(4, 4, CANARY_TEXELS)


def holds_canary_colours(blob):
    """The canary read as COLOR_0 gives three RGBA8 colours; mesh optimisation may reorder the vertices, so
    each 4-byte colour is looked for on its own."""
    return all(CANARY[i:i + 4] in blob for i in range(0, len(CANARY), 4))


_MESHOPT = None


def meshoptimizer():
    """meshoptimizer's shared library (the decoder the engine uses), loaded once through ctypes."""
    global _MESHOPT
    if _MESHOPT is None:
        name = ctypes.util.find_library("meshoptimizer")
        if not name:
            raise SystemExit("cli_hostile.py: libmeshoptimizer is needed to decode pack vertices")
        _MESHOPT = ctypes.CDLL(name)
        _MESHOPT.meshopt_decodeVertexBuffer.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t,
                                                        ctypes.c_char_p, ctypes.c_size_t]
        _MESHOPT.meshopt_decodeVertexBuffer.restype = ctypes.c_int
    return _MESHOPT


_ZSTD = None


def unzstd(stored, size):
    """A zstd section's decoded bytes (pack format 7: header, frame sizes, frames), through libzstd via ctypes."""
    global _ZSTD
    if _ZSTD is None:
        name = ctypes.util.find_library("zstd")
        if not name:
            raise SystemExit("cli_hostile.py: libzstd is needed to decode compressed pack sections")
        _ZSTD = ctypes.CDLL(name)
        _ZSTD.ZSTD_decompress.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_size_t]
        _ZSTD.ZSTD_decompress.restype = ctypes.c_size_t
    chunk, frames, _ = struct.unpack_from("<IIQ", stored, 0)
    at, out = 16 + 4 * frames, b""
    for n in struct.unpack_from(f"<{frames}I", stored, 16):
        dst = ctypes.create_string_buffer(min(chunk, size - len(out)))
        if _ZSTD.ZSTD_decompress(dst, len(dst), stored[at:at + n], n) != len(dst):
            raise SystemExit("cli_hostile.py: a zstd frame of a written pack does not decode")
        out += dst.raw
        at += n
    return out


def decoded_vertices(pack):
    """A pack's vertex records as the reader decodes them (pack format 7: each section raw or zstd; each mesh's
    "vertices" stream meshoptimizer-encoded, located by its "meshEncoding" record), concatenated; b"" for what is
    not a pack. Canary bytes that reached the pack are looked for here: in the encoded streams they would not show."""
    if len(pack) < 64 or pack[:4] != b"VBPK":
        return b""
    sections = {}
    for i in range(struct.unpack_from("<I", pack, 16)[0]):
        name, offset, size, count, _, _, stored, encoding, _ = struct.unpack_from("<16sQQQIIQII", pack, 64 + 64 * i)
        data = pack[offset:offset + stored]
        sections[name.rstrip(b"\0").decode()] = (unzstd(data, size) if encoding == 1 else data, count)
    if "meshEncoding" not in sections or "vertices" not in sections:
        return b""
    encoding, meshes = sections["meshEncoding"]
    vertices = sections["vertices"][0]
    out = b""
    for m in range(meshes):
        byte, nbytes, _, _, count = struct.unpack_from("<QQQQI", encoding, 48 * m)
        dst = ctypes.create_string_buffer(count * 32)
        src = vertices[byte:byte + nbytes]
        if meshoptimizer().meshopt_decodeVertexBuffer(dst, count, 32, src, len(src)) != 0:
            raise SystemExit(f"cli_hostile.py: mesh {m} of a written pack does not decode")
        out += dst.raw
    return out


class Outcome:
    def __init__(self, code, stdout, stderr, seconds, rss_kib, timed_out, files):
        self.code, self.stdout, self.stderr = code, stdout, stderr
        self.seconds, self.rss_kib, self.timed_out, self.files = seconds, rss_kib, timed_out, files


def run(cmd, out_dir):
    """Runs cmd with stdin closed and stdout / stderr in files; kills it past the time limit. Returns its exit
    code (negative: a signal), outputs, wall time and its own peak RSS (os.wait4's rusage, this child only)."""
    os.makedirs(out_dir, exist_ok=True)
    so_path, se_path = os.path.join(out_dir, ".stdout"), os.path.join(out_dir, ".stderr")
    with open(so_path, "wb") as so, open(se_path, "wb") as se:
        start = time.monotonic()
        proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=so, stderr=se, cwd=out_dir)
        timed_out = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() - start > TIME_LIMIT_S:
                timed_out = True
                proc.kill()
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.005)
        seconds = time.monotonic() - start
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here; keep Popen from waiting again
    with open(so_path, "rb") as f:
        stdout = f.read()
    with open(se_path, "rb") as f:
        stderr = f.read()
    os.remove(so_path)
    os.remove(se_path)
    files = {}
    for root, _, names in os.walk(out_dir):
        for name in names:
            path = os.path.join(root, name)
            if os.path.isfile(path) and not os.path.islink(path):
                with open(path, "rb") as f:
                    files[os.path.relpath(path, out_dir)] = f.read()
    return Outcome(proc.returncode, stdout, stderr, seconds, usage.ru_maxrss, timed_out, files)


class Suite:
    def __init__(self, visbuf, data, work):
        self.visbuf, self.data, self.work = visbuf, data, work
        self.failures = []
        self.count = 0

    def fail(self, case, what, outcome=None):
        text = f"FAIL {case}: {what}"
        if outcome is not None:
            text += (f"\n  exit {outcome.code}, {outcome.seconds:.2f} s, {outcome.rss_kib} KiB"
                     f"\n  stderr: {outcome.stderr.decode(errors='replace').strip()[-2000:]}")
        self.failures.append(text)
        print(text, flush=True)

    # -- set-up ---------------------------------------------------------------------------------------------
    def fresh(self, case):
        """A case folder: asset/ (a copy of tests/data/hostile), out/, and the canaries next to asset/."""
        root = os.path.join(self.work, case)
        shutil.rmtree(root, ignore_errors=True)
        os.makedirs(root)
        asset = os.path.join(root, "asset")
        shutil.copytree(self.data, asset)
        self.place_canaries(root, CANARY)
        for template in [n for n in os.listdir(asset) if n.endswith(".gltf.in")]:
            with open(os.path.join(asset, template)) as f:
                text = f.read()
            text = text.replace("@CANARY@", os.path.join(root, "canary.bin"))
            text = text.replace("@CANARY_PNG@", os.path.join(root, "canary.png"))
            with open(os.path.join(asset, template[:-3]), "w") as f:
                f.write(text)
        os.symlink("../canary.bin", os.path.join(asset, "link.bin"))
        os.symlink("../canary.png", os.path.join(asset, "link.png"))
        os.symlink("..", os.path.join(asset, "up"))
        os.mkfifo(os.path.join(asset, "fifo.bin"))
        os.mkfifo(os.path.join(asset, "fifo.png"))
        os.mkfifo(os.path.join(asset, "fifo.gltf"))
        os.mkfifo(os.path.join(asset, "fifo.vbp"))
        return root

    @staticmethod
    def place_canaries(root, canary_bin):
        for name in ("canary.bin", "canary.png"):
            path = os.path.join(root, name)
            if os.path.exists(path):
                os.remove(path)
        if canary_bin is not None:
            with open(os.path.join(root, "canary.bin"), "wb") as f:
                f.write(canary_bin)
            with open(os.path.join(root, "canary.png"), "wb") as f:
                f.write(CANARY_PNG if canary_bin == CANARY else CANARY_PNG + b"trailing bytes change the size")

    # -- checks ---------------------------------------------------------------------------------------------
    def check_refused(self, case, outcome, pattern):
        """Exit 1, the message, time, memory, no canary anywhere, no pack."""
        self.count += 1
        ok = True
        if outcome.timed_out:
            self.fail(case, f"still running after {TIME_LIMIT_S} s (killed)", outcome)
            return False
        if outcome.code != 1:
            self.fail(case, f"exit code {outcome.code}, expected 1" + (" (a crash)" if outcome.code < 0 or
                                                                       outcome.code > 2 else ""), outcome)
            ok = False
        if not re.search(pattern, outcome.stderr.decode(errors="replace")):
            self.fail(case, f"stderr does not match /{pattern}/", outcome)
            ok = False
        if outcome.rss_kib >= RSS_LIMIT_KIB:
            self.fail(case, f"peak RSS {outcome.rss_kib} KiB >= 1 GiB", outcome)
            ok = False
        for name, blob in [("stdout", outcome.stdout), ("stderr", outcome.stderr)] + sorted(outcome.files.items()):
            for label, secret in [("canary.bin", CANARY), ("canary.bin (other size)", CANARY_OTHER_SIZE[:24]),
                                  ("canary.png", CANARY_PNG), ("canary.png texels", CANARY_TEXELS[:16])]:
                if secret in blob:
                    self.fail(case, f"the bytes of {label} appear in {name}", outcome)
                    ok = False
        for name, blob in sorted(outcome.files.items()):
            if holds_canary_colours(blob) or holds_canary_colours(decoded_vertices(blob)):
                self.fail(case, f"the canary's three 4-byte colours appear in {name}", outcome)
                ok = False
        if "out.vbp" in outcome.files:
            self.fail(case, "a pack was written", outcome)
            ok = False
        if ok:
            print(f"ok   {case}: exit 1 in {outcome.seconds:.2f} s, {outcome.rss_kib // 1024} MiB: "
                  f"{outcome.stderr.decode(errors='replace').strip().splitlines()[-1][:160]}", flush=True)
        return ok

    def bake(self, root, file_name, *extra):
        out = os.path.join(root, "out")
        shutil.rmtree(out, ignore_errors=True)
        return run([self.visbuf, "bake", os.path.join(root, "asset", file_name), "-o", os.path.join(out, "out.vbp"),
                    *extra], out)

    # -- cases ----------------------------------------------------------------------------------------------
    def traversal(self, case, file_name, uri_shown, kind):
        root = self.fresh(case)
        pattern = rf"{kind}: uri '{re.escape(uri_shown)}' resolves outside the asset's folder"
        messages = []
        for state, canary in [("canary present", CANARY), ("canary of another size", CANARY_OTHER_SIZE),
                              ("no canary", None)]:
            self.place_canaries(root, canary)
            outcome = self.bake(root, file_name)
            if not self.check_refused(f"{case} ({state})", outcome, pattern):
                return
            messages.append(outcome.stderr)
        self.count += 1
        if len(set(messages)) != 1:
            self.fail(case, "the message differs with what is outside the folder:\n" +
                      "\n".join(m.decode(errors="replace") for m in messages))
        else:
            print(f"ok   {case}: the same message with the canary present, resized and absent", flush=True)
        # Positive control: allowed explicitly, the same file bakes and the canary reaches the pack.
        self.place_canaries(root, CANARY)
        # Images are stored as RGBA8 here so their texels stay verbatim (block compression would hide them).
        raw_textures = () if kind.startswith("buffer") else ("--textures", "rgba8")
        outcome = self.bake(root, file_name, "--allow-uri-root", root, *raw_textures)
        self.count += 1
        pack = outcome.files.get("out.vbp", b"")
        leaked = holds_canary_colours(decoded_vertices(pack)) if kind.startswith("buffer") else CANARY_TEXELS in pack
        if outcome.code != 0 or not leaked:
            self.fail(case + " (control: --allow-uri-root)", "expected a pack holding the canary's bytes", outcome)
        else:
            print(f"ok   {case} (control): with --allow-uri-root the canary's bytes reach the pack", flush=True)

    def simple(self, case, file_name, pattern, *extra):
        root = self.fresh(case)
        self.check_refused(case, self.bake(root, file_name, *extra), pattern)

    def fifo_inputs(self):
        root = self.fresh("fifo_input")
        self.check_refused("fifo as bake input", self.bake(root, "fifo.gltf"),
                           r"fifo\.gltf: not a regular file \(a FIFO\)")
        for name in ("fifo.gltf", "fifo.vbp"):
            out = os.path.join(root, "out")
            shutil.rmtree(out, ignore_errors=True)
            outcome = run([self.visbuf, "render", "--scene", os.path.join(root, "asset", name), "--size", "64x64",
                           "-o", os.path.join(out, "out.png")], out)
            self.check_refused(f"render --scene {name} (a FIFO)", outcome,
                               rf"{re.escape(name)}: not a regular file \(a FIFO\)")
        self.check_refused("folder as bake input", run([self.visbuf, "bake", os.path.join(root, "asset"), "-o",
                                                         os.path.join(root, "out", "out.vbp")],
                                                        os.path.join(root, "out")),
                           r"not a regular file \(a directory\)")

    def all_cases(self):
        yield "buffer_traversal", lambda: self.traversal("buffer_traversal", "buffer_traversal.gltf",
                                                         "../canary.bin", "buffer 1")
        yield "buffer_traversal_encoded", lambda: self.traversal(
            "buffer_traversal_encoded", "buffer_traversal_encoded.gltf", "..%2Fcanary.bin", "buffer 1")
        yield "buffer_absolute", lambda: self.traversal(
            "buffer_absolute", "buffer_absolute.gltf", os.path.join(self.work, "buffer_absolute", "canary.bin"),
            "buffer 1")
        yield "buffer_symlink", lambda: self.traversal("buffer_symlink", "buffer_symlink.gltf", "link.bin",
                                                       "buffer 1")
        yield "buffer_symlink_dir", lambda: self.traversal("buffer_symlink_dir", "buffer_symlink_dir.gltf",
                                                           "up/canary.bin", "buffer 1")
        yield "image_traversal", lambda: self.traversal("image_traversal", "image_traversal.gltf", "../canary.png",
                                                        "image 0")
        yield "image_traversal_encoded", lambda: self.traversal(
            "image_traversal_encoded", "image_traversal_encoded.gltf", "%2E%2E%2Fcanary.png", "image 0")
        yield "image_absolute", lambda: self.traversal(
            "image_absolute", "image_absolute.gltf", os.path.join(self.work, "image_absolute", "canary.png"),
            "image 0")
        yield "image_symlink", lambda: self.traversal("image_symlink", "image_symlink.gltf", "link.png", "image 0")
        yield "image_bomb", lambda: self.simple(
            "image_bomb", "image_bomb.gltf",
            r"image 0 'image_bomb\.png': 16384x16384 = 268435456 pixels exceeds the image pixel budget of 67108864")
        yield "max_image_pixels_option", lambda: self.simple(
            "max_image_pixels_option", "truncated_jpeg.gltf", r"32x32 = 1024 pixels exceeds the image pixel budget of 1000",
            "--max-image-pixels", "1000")
        yield "truncated_jpeg", lambda: self.simple(
            "truncated_jpeg", "truncated_jpeg.gltf",
            r"image 0 'truncated\.jpg': truncated or corrupt image: .*Premature end of JPEG file", "--strict-images")
        yield "fifo_buffer", lambda: self.simple(
            "fifo_buffer", "fifo_buffer.gltf", r"buffer 1: uri 'fifo\.bin': not a regular file \(a FIFO\)")
        yield "fifo_image", lambda: self.simple(
            "fifo_image", "fifo_image.gltf", r"image 'fifo\.png': '.*fifo\.png' is not a regular file \(a FIFO\)")
        yield "fifo_input", self.fifo_inputs
        yield "version_1_0", lambda: self.simple(
            "version_1_0", "version_1_0.gltf", r"asset\.version '1\.0' is not supported \(only glTF 2\.x\)")
        yield "node_cycle", lambda: self.simple(
            "node_cycle", "node_cycle.gltf", r"node 1 'a' is its own ancestor \(the node graph has a cycle\)")
        yield "huge_positions", lambda: self.simple(
            "huge_positions", "huge_positions.gltf",
            r"vertex 1 at \(3e\+38, 0, 0\) is too far from the origin \(\|coordinate\| > 1e\+18\)")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--visbuf", required=True, help="the visbuf program")
    parser.add_argument("--data", default=os.path.join(here, "data", "hostile"), help="tests/data/hostile")
    parser.add_argument("--work", default=None, help="scratch folder (default: a temporary one, removed)")
    parser.add_argument("-k", default="", help="run only the cases whose name contains this")
    args = parser.parse_args()
    visbuf = os.path.abspath(args.visbuf)
    scratch = None
    if args.work:
        work = os.path.abspath(args.work)
        shutil.rmtree(work, ignore_errors=True)
        os.makedirs(work)
    else:
        scratch = tempfile.mkdtemp(prefix="visbuf_hostile_")
        work = scratch
    suite = Suite(visbuf, os.path.abspath(args.data), work)
    try:
        for name, case in suite.all_cases():
            if args.k in name:
                case()
    finally:
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)
    print(f"{suite.count} checks, {len(suite.failures)} failed")
    return 1 if suite.failures else 0


if __name__ == "__main__":
    sys.exit(main())
