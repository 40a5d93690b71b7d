#!/usr/bin/env python3
"""Markdown tables for scripts/bench_skinning.sh: skinning cost per vertex and per instance, and the static
scene's frame time with and without the skinning code present (median of the alternating rounds)."""
import glob
import json
import os
import statistics
import sys

out = sys.argv[1]
rows = []
for path in glob.glob(os.path.join(out, "fox_*.json")):
    j = json.load(open(path))
    s = j.get("stats", j)
    skin = s["passMs"].get("skin", 0.0)
    n, verts = s["skinnedInstances"], s["skinnedVertices"]
    rows.append((n, verts, skin, s["animationCpuMs"], s["gpuMs"], s["cpuRecordMs"], s["trianglesDrawn"], s["device"]))
rows.sort()
if rows:
    print(f"Device: {rows[0][7]}\n")
    print("| instances | skinned vertices | skin pass ms | ns / vertex | poses CPU ms | us / instance (GPU + CPU) "
          "| frame GPU ms | triangles drawn |")
    print("|---|---|---|---|---|---|---|---|")
    for n, verts, skin, cpu, gpu, rec, tris, _ in rows:
        print(f"| {n:,} | {verts:,} | {skin:.3f} | {1e6 * skin / verts:.3f} | {cpu:.2f} | "
              f"{1e3 * (skin + cpu) / n:.3f} | {gpu:.2f} | {tris:,} |")


def frame_ms(pattern):
    vals = []
    for path in sorted(glob.glob(os.path.join(out, pattern))):
        j = json.load(open(path))
        s = j.get("stats", j)
        vals.append(s["gpuMs"] + s["cpuRecordMs"])
    return vals


with_ = frame_ms("static_with_*.json")
without = frame_ms("static_without_*.json")
if with_:
    print("\nStatic field, 100,000 knots, 1280x720 (frame ms = GPU passes + CPU record; median of the rounds):\n")
    print("| binary | rounds | frame ms (median) | all rounds |")
    print("|---|---|---|---|")
    print(f"| with skinning code (skipped) | {len(with_)} | {statistics.median(with_):.3f} | "
          f"{', '.join(f'{v:.3f}' for v in with_)} |")
    if without:
        print(f"| without skinning code | {len(without)} | {statistics.median(without):.3f} | "
              f"{', '.join(f'{v:.3f}' for v in without)} |")
        print(f"\nRatio with/without: {statistics.median(with_) / statistics.median(without):.3f}")
