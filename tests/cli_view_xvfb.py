#!/usr/bin/env python3
"""`visbuf view` in a virtual X server: presents, validates, and shows what `visbuf render` renders.

Starts its own Xvfb on a free display number (stopped at exit), runs
`visbuf view --validation --screenshot A.png --frames 30 --size 320x240` on the default field scene with a
fixed camera, then `visbuf render` of the same camera and size to B.png, and requires: both exit 0, the viewer
printed `presented 30 frames` and `validation messages: 0` (and no validation line on stderr), and
`oiiotool --diff` of A.png against B.png gives a PSNR of at least 40 dB. Also checks that without a display
the viewer exits non-zero with its one-line "no display" message, and that the debug view `--view objects`
presents the image `visbuf render --view objects` writes (PSNR >= 40 dB).

usage: cli_view_xvfb.py VISBUF OUT_FOLDER
"""
import atexit
import math
import os
import re
import shutil
import subprocess
import sys
import time

CAMERA = ["--camera-pos", "0,20,120", "--camera-target", "0,0,0"]
SIZE = ["--size", "320x240"]
FRAMES = 30
MIN_PSNR = 40.0


def fail(message):
    print(f"cli_view_xvfb: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def start_xvfb(xvfb):
    """Starts Xvfb on the first free display number from 90; returns (process, number)."""
    for number in range(90, 190):
        if os.path.exists(f"/tmp/.X{number}-lock") or os.path.exists(f"/tmp/.X11-unix/X{number}"):
            continue
        proc = subprocess.Popen([xvfb, f":{number}", "-screen", "0", "1280x720x24", "-nolisten", "tcp"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 15.0
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                break  # taken by another server meanwhile: try the next number
            if os.path.exists(f"/tmp/.X11-unix/X{number}"):
                return proc, number
            time.sleep(0.1)
        if proc.poll() is None:
            stop(proc)
    fail("no free X display number in :90..:189 (or Xvfb does not start)")


def stop(proc):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def run(args, env, timeout=300):
    r = subprocess.run(args, env=env, capture_output=True, text=True, timeout=timeout)
    return r.returncode, r.stdout, r.stderr


def main():
    if len(sys.argv) != 3:
        fail("usage: cli_view_xvfb.py VISBUF OUT_FOLDER")
    visbuf, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    xvfb = shutil.which("Xvfb")
    if not xvfb:
        fail("Xvfb is not installed (apt-get install xvfb; scripts/deps.txt)")
    oiiotool = shutil.which("oiiotool")
    if not oiiotool:
        fail("oiiotool is not installed (apt-get install openimageio-tools; scripts/deps.txt)")

    # Without a display: one clear line, non-zero exit, before any work.
    bare = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    rc, so, se = run([visbuf, "view", *SIZE], bare, timeout=60)
    if rc == 0 or "no display" not in se or "visbuf render" not in se:
        fail(f"view without a display: expected a non-zero exit and the 'no display' line, got {rc}:\n{so}{se}")

    proc, number = start_xvfb(xvfb)
    atexit.register(stop, proc)
    env = dict(bare, DISPLAY=f":{number}")

    a = os.path.join(out, "A.png")
    b = os.path.join(out, "B.png")
    for f in (a, b):
        if os.path.exists(f):
            os.remove(f)
    rc, so, se = run([visbuf, "view", "--validation", "--screenshot", a, "--frames", str(FRAMES), *SIZE, *CAMERA], env)
    print(so, end="")
    print(se, end="", file=sys.stderr)
    if rc != 0:
        fail(f"visbuf view exited {rc}")
    if not re.search(rf"^presented {FRAMES} frames$", so, re.M):
        fail(f"visbuf view did not print 'presented {FRAMES} frames'")
    m = re.search(r"^validation messages: (\d+)$", so, re.M)
    if not m:
        fail("visbuf view --validation did not print its validation message count")
    if int(m.group(1)) != 0 or "validation:" in se:
        fail(f"visbuf view: {m.group(1)} validation message(s)")
    if not os.path.exists(a):
        fail("visbuf view wrote no screenshot")

    rc, so, se = run([visbuf, "render", "--validation", "-o", b, *SIZE, *CAMERA], env)
    if rc != 0:
        fail(f"visbuf render exited {rc}:\n{so}{se}")

    r = subprocess.run([oiiotool, "-v", a, b, "--diff"], capture_output=True, text=True, timeout=60)
    m = re.search(r"Peak SNR = (\S+)", r.stdout)
    if not m:
        fail(f"oiiotool --diff printed no PSNR:\n{r.stdout}{r.stderr}")
    psnr = float(m.group(1))  # "inf" for identical images
    print(f"cli_view_xvfb: {FRAMES} frames presented, 0 validation messages, "
          f"screenshot vs render PSNR {'inf' if math.isinf(psnr) else f'{psnr:.1f}'} dB")
    if not psnr >= MIN_PSNR:
        fail(f"screenshot vs render: PSNR {psnr} dB < {MIN_PSNR} dB:\n{r.stdout}")

    # A debug view (key V, or --view): the viewer presents render --view's image of the same frame.
    c = os.path.join(out, "C.png")
    d = os.path.join(out, "D.png")
    for f in (c, d):
        if os.path.exists(f):
            os.remove(f)
    rc, so, se = run([visbuf, "view", "--validation", "--view", "objects", "--screenshot", c, "--frames", "3", *SIZE,
                      *CAMERA], env)
    if rc != 0 or not re.search(r"^presented 3 frames$", so, re.M) or "validation messages: 0" not in so:
        fail(f"visbuf view --view objects exited {rc}:\n{so}{se}")
    rc, so, se = run([visbuf, "render", "--validation", "--view", "objects", "-o", d, *SIZE, *CAMERA], env)
    if rc != 0:
        fail(f"visbuf render --view objects exited {rc}:\n{so}{se}")
    r = subprocess.run([oiiotool, "-v", c, d, "--diff"], capture_output=True, text=True, timeout=60)
    m = re.search(r"Peak SNR = (\S+)", r.stdout)
    if not m or not float(m.group(1)) >= MIN_PSNR:
        fail(f"view --view objects vs render --view objects:\n{r.stdout}{r.stderr}")
    print(f"cli_view_xvfb: debug view 'objects' presented, vs render --view objects PSNR {m.group(1)} dB")


if __name__ == "__main__":
    main()
