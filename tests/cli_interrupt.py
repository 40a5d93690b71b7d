#!/usr/bin/env python3
"""A bake interrupted while it writes its pack leaves the old pack intact and no temporary file.

  SIGINT, SIGTERM: the signal handler of the pack writer removes ".NAME.tmpPID.N" before the process ends
                   with the signal; the old pack is byte-identical, and no temporary file is left.
  SIGKILL:         no handler runs, so the temporary file stays; the old pack is byte-identical; the next bake
                   to the same output removes it (its PID is dead), and keeps a temporary file of a live PID.

The input is generated: a glTF quad with two 4096x4096 PNG textures (tiny files, one colour each), baked at
--max-texture-size 4096 and --compression-level 0 into a pack of about 180 MB (one-colour textures compress to
almost nothing), so that the temporary file exists for a while (the test waits for it to appear, then signals).
The old pack is baked at --max-texture-size 1024, so it differs from what the interrupted bake would write.
Should a bake finish before the signal lands (the process ends 0, or the signal lands after the rename: the pack
is then the complete new pack, byte-identical to a reference bake), the attempt is repeated.

usage: cli_interrupt.py VISBUF OUT_FOLDER
"""
import hashlib
import json
import os
import signal
import subprocess
import sys
import time

from gltf_fixtures import quad_buffers, write_png

ATTEMPTS = 5


def write_gltf(folder):
    write_png(os.path.join(folder, "a.png"), 4096, 4096, (200, 100, 50))
    write_png(os.path.join(folder, "b.png"), 4096, 4096, (20, 100, 250))
    gltf = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"name": "quad", "primitives": [
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
                       "emissiveTexture": {"index": 1}, "emissiveFactor": [1, 1, 1]}],
        "textures": [{"source": 0}, {"source": 1}], "images": [{"uri": "a.png"}, {"uri": "b.png"}],
        **quad_buffers(),
    }
    path = os.path.join(folder, "big.gltf")
    with open(path, "w") as f:
        json.dump(gltf, f)
    return path


def sha256(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def temp_files(folder, name):
    return sorted(f for f in os.listdir(folder) if f.startswith("." + name + ".tmp"))


def default_signals():
    # The child starts with the default disposition whatever the test runner ignores (a shell's background
    # jobs ignore SIGINT): the pack writer only installs its handler over the default one.
    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, signal.SIG_DFL)


def main():
    visbuf, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    for f in os.listdir(out):
        p = os.path.join(out, f)
        if os.path.isfile(p) or os.path.islink(p):
            os.remove(p)
    gltf = write_gltf(out)
    pack = os.path.join(out, "big.vbp")
    name = os.path.basename(pack)
    failures = []

    def bake(size, extra=()):
        return subprocess.run([visbuf, "bake", gltf, "-o", pack, "--max-texture-size", str(size), *extra],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)

    big_args = ["--max-texture-size", "4096", "--compression-level", "0"]
    reference = os.path.join(out, "reference.vbp")
    r = subprocess.run([visbuf, "bake", gltf, "-o", reference, *big_args],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"the reference bake failed ({r.returncode}): {r.stderr}")
    new = sha256(reference)
    os.remove(reference)

    r = bake(1024)
    if r.returncode != 0:
        sys.exit(f"the first bake failed ({r.returncode}): {r.stderr}")
    old = sha256(pack)
    if old == new:
        sys.exit("the old pack and the interrupted bake's pack are the same: the test cannot tell them apart")

    def interrupt(sig):
        """Bakes at 4096 and sends `sig` once the temporary file exists; returns the temporary files seen."""
        for attempt in range(ATTEMPTS):
            p = subprocess.Popen([visbuf, "bake", gltf, "-o", pack, *big_args],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                 preexec_fn=default_signals)
            seen = []
            deadline = time.monotonic() + 300
            while p.poll() is None and time.monotonic() < deadline:
                seen = temp_files(out, name)
                if seen:
                    p.send_signal(sig)
                    break
                time.sleep(0.002)
            _, err = p.communicate(timeout=300)
            renamed = sha256(pack) == new
            if seen and p.returncode == -sig and not renamed:
                return seen
            if p.returncode == 0 or (p.returncode == -sig and renamed):
                # The write finished (and the complete new pack was renamed into place) before the signal
                # landed: that is the atomic write's other allowed outcome, not the one this test is after.
                print(f"  attempt {attempt + 1}: the pack was in place before {sig.name} landed; again")
                r = bake(1024)
                if r.returncode != 0 or sha256(pack) != old:
                    sys.exit(f"re-baking the old pack failed ({r.returncode}): {r.stderr}")
                continue
            sys.exit(f"the bake interrupted by {sig.name} ended with {p.returncode} "
                     f"(expected {-sig}, temporary files seen: {seen}): {err}")
        sys.exit(f"no bake could be interrupted by {sig.name} while writing in {ATTEMPTS} attempts")

    for sig in (signal.SIGINT, signal.SIGTERM):
        t0 = time.monotonic()
        seen = interrupt(sig)
        left = temp_files(out, name)
        if sha256(pack) != old:
            failures.append(f"{sig.name}: the old pack changed")
        if left:
            failures.append(f"{sig.name}: temporary files left: {left}")
        print(f"{sig.name}: interrupted while {seen[0]} existed; old pack intact: {sha256(pack) == old}; "
              f"left: {left or 'nothing'} ({time.monotonic() - t0:.1f} s)")

    # SIGKILL: the temporary file stays (no handler can run); the next bake removes it.
    seen = interrupt(signal.SIGKILL)
    left = temp_files(out, name)
    if sha256(pack) != old:
        failures.append("SIGKILL: the old pack changed")
    if not left:
        failures.append("SIGKILL: no temporary file was left (the test did not interrupt the write)")
    print(f"SIGKILL: interrupted while {seen[0]} existed; old pack intact: {sha256(pack) == old}; left: {left}")
    # Beside it: a temporary file of a live process (this test's own PID) must be kept; one of a dead one removed.
    dead = subprocess.Popen(["true"])
    dead.wait()
    live_file = os.path.join(out, f".{name}.tmp{os.getpid()}.0")
    dead_file = os.path.join(out, f".{name}.tmp{dead.pid}.7")
    for f in (live_file, dead_file):
        with open(f, "wb") as h:
            h.write(b"partial")
    r = bake(1024, ["--no-textures"])
    after = temp_files(out, name)
    if r.returncode != 0:
        failures.append(f"the bake after SIGKILL failed ({r.returncode}): {r.stderr}")
    if any(f in after for f in left) or os.path.basename(dead_file) in after:
        failures.append(f"after the next bake, stale temporary files are still there: {after}")
    if os.path.basename(live_file) not in after:
        failures.append("the next bake removed the temporary file of a live process")
    print(f"next bake: temporary files left: {after} (the live process's, kept)")
    os.remove(live_file)

    if failures:
        sys.exit("cli_interrupt: " + "; ".join(failures))
    print("cli_interrupt: ok")


if __name__ == "__main__":
    main()
