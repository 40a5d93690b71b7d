#!/usr/bin/env python3
"""KHR_draco_mesh_compression end to end: each asset's Draco twin, made here with Debian's draco_transcoder at
stated quantisation bits, renders through visbuf like its uncompressed original.

For each asset: `draco_transcoder -i ORIGINAL -o TWIN.glb -qp 16 -qt 14 -qn 12 -qc 10 -qw 12`, then
`visbuf render --scene FILE --validation --size 240x180` (default camera: framed on the scene's bounds, which
quantisation moves by less than 2^-16 of their extent) of both, and `oiiotool --diff` of the two images: the
PSNR must be at least MIN_PSNR. Measured (lavapipe): CesiumMilkTruck 49.5 dB, CesiumMan 39.4 dB (texture
edges on the head move with the 14-bit texture coordinates; a few silhouette pixels flip); a wrong point order,
attribute or index permutation scrambles the mesh and falls far below. Fox is not rendered here: it has no
normals, and the transcoder welds the vertices the original keeps apart, so the generated normals differ (the
unit test compares its triangles, skin included). The twin's render must print no validation message. Also
../shared/assets' Box/glTF-Draco against Box/glTF when VISBUF_EXTRA_ASSETS names that corpus.

usage: cli_draco_twins.py VISBUF ASSETS OUT_FOLDER
"""
import math
import os
import re
import shutil
import subprocess
import sys

MIN_PSNR = 36.0
SIZE = ["--size", "240x180"]
BITS = ["-qp", "16", "-qt", "14", "-qn", "12", "-qc", "10", "-qw", "12"]
ASSETS = ["BoxInterleaved/glTF/BoxInterleaved.gltf", "CesiumMan/glTF/CesiumMan.gltf",
          "CesiumMilkTruck/glTF-Binary/CesiumMilkTruck.glb", "MultiUVTest/glTF/MultiUVTest.gltf"]


def fail(message):
    print(f"cli_draco_twins: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    return r.returncode, r.stdout, r.stderr


def render(visbuf, scene, png):
    rc, so, se = run([visbuf, "render", "--scene", scene, "--validation", *SIZE, "-o", png])
    if rc != 0 or not os.path.exists(png):
        fail(f"visbuf render --scene {scene} exited {rc}:\n{so}{se}")
    if "validation:" in se:
        fail(f"visbuf render --scene {scene}: validation message:\n{se}")


def psnr(oiiotool, a, b):
    r = subprocess.run([oiiotool, "-v", a, b, "--diff"], capture_output=True, text=True, timeout=60)
    m = re.search(r"Peak SNR = (\S+)", r.stdout)
    if not m:
        fail(f"oiiotool --diff printed no PSNR:\n{r.stdout}{r.stderr}")
    return float(m.group(1))  # "inf" for identical images


def main():
    if len(sys.argv) != 4:
        fail("usage: cli_draco_twins.py VISBUF ASSETS OUT_FOLDER")
    visbuf, assets, out = sys.argv[1:]
    transcoder, oiiotool = shutil.which("draco_transcoder"), shutil.which("oiiotool")
    if not transcoder or not oiiotool:
        fail("draco_transcoder and oiiotool are needed (scripts/deps.txt: draco, openimageio-tools)")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    pairs = []
    for asset in ASSETS:
        original = os.path.join(assets, asset)
        name = os.path.splitext(os.path.basename(asset))[0]
        twin = os.path.join(out, name + ".draco.glb")
        rc, so, se = run([transcoder, "-i", original, "-o", twin, *BITS])
        if rc != 0:
            fail(f"draco_transcoder {asset} exited {rc}:\n{so}{se}")
        pairs.append((name, original, twin))
    for corpus in filter(None, os.environ.get("VISBUF_EXTRA_ASSETS", "").split(":")):
        draco = os.path.join(corpus, "Box", "glTF-Draco", "Box.gltf")
        if os.path.exists(draco):
            pairs.append(("Box (glTF-Draco)", os.path.join(corpus, "Box", "glTF", "Box.gltf"), draco))
            break
    for name, original, twin in pairs:
        a, b = os.path.join(out, f"{name}.png"), os.path.join(out, f"{name}.draco.png")
        render(visbuf, original, a)
        render(visbuf, twin, b)
        db = psnr(oiiotool, a, b)
        print(f"cli_draco_twins: {name}: twin {os.path.getsize(twin)} bytes, "
              f"render vs original PSNR {'inf' if math.isinf(db) else f'{db:.1f}'} dB")
        if not db >= MIN_PSNR:
            fail(f"{name}: Draco twin vs original PSNR {db} dB < {MIN_PSNR} dB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
