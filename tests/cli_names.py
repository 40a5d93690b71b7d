#!/usr/bin/env python3
"""Names from an asset are printed to the terminal with their control characters escaped.

A generated glTF whose mesh, material, image, node and file names, and an alphaMode string, carry escape
sequences (ESC [31m, OSC 0 ... BEL), newlines, DEL and a C1 CSI (U+009B) is baked and rendered. Neither
command may print a control byte other than the newline ending each line (nor a UTF-8 C1 character); each
name must appear escaped as \\xNN (one per byte); plain UTF-8 names are printed unchanged.

usage: cli_names.py VISBUF OUT_FOLDER
"""
import json
import os
import re
import subprocess
import sys

from gltf_fixtures import quad_buffers, write_png

MESH = "evil\u001b[31m\nmesh"
MESH_ESCAPED = r"evil\x1b[31m\x0amesh"
PLAIN = "caf\u00e9 \u2713"  # valid UTF-8, printed as it is
MATERIAL = "mat\u009b2J\u007f"
MATERIAL_ESCAPED = r"mat\xc2\x9b2J\x7f"
ALPHA = "EVIL\u001b[0m"
ALPHA_ESCAPED = r"EVIL\x1b[0m"
IMAGE = "img\u001b[2J"
IMAGE_ESCAPED = r"img\x1b[2J"
NODE = "zero\u001b]0;pwned\u0007"
NODE_ESCAPED = r"zero\x1b]0;pwned\x07"
FILE = "n\u001b[1m.gltf"
FILE_ESCAPED = r"n\x1b[1m.gltf"


def write_gltf(folder):
    write_png(os.path.join(folder, "t.png"), 4, 4, (10, 200, 30))
    triangles = {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}
    points = {"attributes": {"POSITION": 0}, "mode": 0}  # skipped with a warning naming the mesh
    gltf = {
        "asset": {"version": "2.0"}, "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "name": "plain node"},
                  {"mesh": 1, "translation": [2, 0, 0]},
                  {"mesh": 0, "name": NODE, "scale": [0, 0, 0]}],  # zero scale: a warning naming the node
        "meshes": [{"name": MESH, "primitives": [triangles, points]},
                   {"name": PLAIN, "primitives": [triangles]}],
        "materials": [{"name": MATERIAL, "alphaMode": ALPHA,  # unknown alphaMode: a warning naming both
                       "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}], "images": [{"uri": "t.png", "name": IMAGE}],
        **quad_buffers(),
    }
    path = os.path.join(folder, FILE)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(gltf, f, ensure_ascii=False)
    return path


# A control byte other than a newline, or a UTF-8 C1 character (U+0080..U+009F).
RAW = re.compile(rb"[\x00-\x09\x0b-\x1f\x7f]|\xc2[\x80-\x9f]")


def run(args, expect, failures):
    r = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = r.stdout + r.stderr
    what = " ".join(a.encode("unicode_escape").decode() for a in args[1:3])
    if r.returncode != 0:
        failures.append(f"{what}: exit {r.returncode}: {out!r}")
    for m in RAW.finditer(out):
        failures.append(f"{what}: raw control byte {m.group()!r} at {m.start()}: "
                        f"...{out[max(0, m.start() - 40):m.start() + 20]!r}...")
    text = out.decode("utf-8", errors="replace")
    for e in expect:
        if e not in text:
            failures.append(f"{what}: '{e}' not printed")
    return text


def main():
    visbuf, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    gltf = write_gltf(out)
    failures = []
    bake = run([visbuf, "bake", gltf, "-o", os.path.join(out, "names.vbp")],
               [MESH_ESCAPED, PLAIN, IMAGE_ESCAPED, MATERIAL_ESCAPED, ALPHA_ESCAPED, NODE_ESCAPED, FILE_ESCAPED],
               failures)
    render = run([visbuf, "render", "--scene", gltf, "--size", "32x32", "-o", ""],
                 [MESH_ESCAPED, MATERIAL_ESCAPED, ALPHA_ESCAPED, NODE_ESCAPED], failures)
    if failures:
        sys.exit("cli_names:\n  " + "\n  ".join(failures) + "\n--- bake:\n" + bake + "\n--- render:\n" + render)
    print(bake)
    print("cli_names: ok")


if __name__ == "__main__":
    main()
