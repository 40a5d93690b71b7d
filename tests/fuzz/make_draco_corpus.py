#!/usr/bin/env python3
"""Writes the seeds of fuzz_draco_decode (corpus/fuzz_draco_decode/): Draco streams made with Debian's draco tools
(the `draco` package), each behind the 6-byte prefix the target reads (point count, face count, the POSITION /
NORMAL attribute ids, the indices component type: see fuzz_draco_decode.cpp), with the stream's true counts so
that the seeds decode. Streams: assets/BoxInterleaved through draco_transcoder (edgebreaker), and a small grid
through draco_encoder at compression levels 10 (edgebreaker, valence traversal) and 0 (sequential).

Usage: make_draco_corpus.py  (run from anywhere; overwrites the seeds)"""
import json
import os
import struct
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
OUT = os.path.join(HERE, "corpus", "fuzz_draco_decode")


def seed(name, points, faces, position_id, normal_id, stream):
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(struct.pack("<HHBB", points, faces, position_id | normal_id << 4, 1) + stream)


def transcoded_box(tmp):
    out = os.path.join(tmp, "box.glb")
    subprocess.run(["draco_transcoder", "-i", os.path.join(REPO, "assets/BoxInterleaved/glTF/BoxInterleaved.gltf"),
                    "-o", out], check=True, stdout=subprocess.DEVNULL)
    data = open(out, "rb").read()
    json_len = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_len])
    binary = data[20 + json_len + 8:]
    prim = doc["meshes"][0]["primitives"][0]
    ext = prim["extensions"]["KHR_draco_mesh_compression"]
    view = doc["bufferViews"][ext["bufferView"]]
    stream = binary[view.get("byteOffset", 0):view.get("byteOffset", 0) + view["byteLength"]]
    points = doc["accessors"][prim["attributes"]["POSITION"]]["count"]
    faces = doc["accessors"][prim["indices"]]["count"] // 3
    return points, faces, ext["attributes"]["POSITION"], ext["attributes"]["NORMAL"], stream


def grid_obj(path, n=6):
    """An n x n grid of quads (two triangles each) with one normal: n*n*2 faces, (n+1)^2 points."""
    with open(path, "w") as f:
        for y in range(n + 1):
            for x in range(n + 1):
                f.write(f"v {x} {y} {0.1 * ((x * y) % 3)}\n")
        f.write("vn 0 0 1\n")
        for y in range(n):
            for x in range(n):
                a = y * (n + 1) + x + 1
                b, c, d = a + 1, a + n + 2, a + n + 1
                f.write(f"f {a}//1 {b}//1 {c}//1\nf {a}//1 {c}//1 {d}//1\n")
    return (n + 1) ** 2, 2 * n * n


def main():
    os.makedirs(OUT, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        seed("box_transcoded.bin", *transcoded_box(tmp))
        obj = os.path.join(tmp, "grid.obj")
        points, faces = grid_obj(obj)
        for level in (10, 0):
            drc = os.path.join(tmp, f"grid{level}.drc")
            subprocess.run(["draco_encoder", "-i", obj, "-o", drc, "-cl", str(level), "-qp", "14"], check=True,
                           stdout=subprocess.DEVNULL)
            # draco's OBJ reader adds POSITION (unique id 0), then NORMAL (1); one normal for every corner makes
            # no seam, so the points are the grid's vertices (checked: the seeds decode to these counts).
            seed(f"grid_cl{level}.bin", points, faces, 0, 1, open(drc, "rb").read())


if __name__ == "__main__":
    main()
