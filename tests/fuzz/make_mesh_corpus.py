#!/usr/bin/env python3
"""Regenerates the seed corpus of fuzz_mesh_build (tests/fuzz/corpus/fuzz_mesh_build/): a few hundred bytes each.

    tests/fuzz/make_mesh_corpus.py

Raw meshes in the target's byte layout (see fuzz_mesh_build.cpp): a fan, stacked copies of one triangle, a grid,
a grid with huge coordinates, slivers and coincident vertices with two normals; and small glTF files of the
hostile classes (tests/hostile_cases/mesh.py): a position-less sparse accessor and a fan GLB.
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "hostile_cases"))
import mesh as hostile  # noqa: E402  (the glTF generators of the hostile suite)

OUT = os.path.join(HERE, "corpus", "fuzz_mesh_build")


def raw(flags, vertices, triangles):
    """flags byte, vertex count (multiple of 4, <= 1024), 3 bytes per vertex, then 2 bytes per index."""
    assert len(vertices) % 4 == 0 and 4 <= len(vertices) <= 1024
    out = bytes([flags, len(vertices) // 4 - 1])
    for v in vertices:
        out += bytes(v)
    for t in triangles:
        for i in t:
            out += bytes([i & 255, i >> 8])
    return out


def main():
    os.makedirs(OUT, exist_ok=True)
    seeds = {}
    rim = [(8 + round(7 * math.cos(2 * math.pi * i / 63)), 8 + round(7 * math.sin(2 * math.pi * i / 63)), 0)
           for i in range(63)]
    seeds["raw_fan"] = raw(0, [(8, 8, 0)] + rim, [(0, 1 + i, 1 + (i + 1) % 63) for i in range(63)])
    seeds["raw_stacked"] = raw(0, [(0, 0, 0), (15, 0, 0), (0, 15, 0), (0, 0, 0)], [(0, 1, 2)])
    grid = [(x * 17, y * 17, (x * y) % 5) for y in range(8) for x in range(8)]
    quads = [(y * 8 + x, y * 8 + x + 1, y * 8 + x + 8) for y in range(7) for x in range(7)]
    quads += [(y * 8 + x + 1, y * 8 + x + 9, y * 8 + x + 8) for y in range(7) for x in range(7)]
    seeds["raw_grid"] = raw(1, grid, quads)
    seeds["raw_huge"] = raw(3, grid, quads)
    seeds["raw_slivers"] = raw(1, [(0, 0, 0), (255, 255, 255), (128, 127, 128), (255, 0, 255)],
                               [(0, 1, 2), (3, 2, 0), (1, 3, 2)])
    seeds["raw_coincident"] = raw(4, [(5, 5, 5)] * 4 + [(9, 2, 1)] * 4, [(0, 1, 4), (2, 3, 5), (0, 6, 7)])
    seeds["gltf_positionless"] = hostile.positionless(3000)
    seeds["glb_fan"] = hostile.fan(48)
    seeds["glb_stacked"] = hostile.stacked(40)
    for name, data in seeds.items():
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
        print(f"{name}: {len(data)} bytes")


if __name__ == "__main__":
    main()
