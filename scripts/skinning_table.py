#!/usr/bin/env python3
"""Markdown tables for scripts/bench_skinning.sh: skinning cost per vertex and per instance with the error of the
skinned vertices against the CPU's double-precision skinning beside it (--skin-check), both kinds of culling
bounds (cost, tightness, objects culled), and the static scene's frame time with and without the skinning code
present (median of the alternating rounds)."""
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
    passes = s["passMs"]
    skin = passes.get("skin", 0.0)
    n, verts = s["skinnedInstances"], s["skinnedVertices"]
    k = j.get("skinCheck", {})
    rows.append(dict(n=n, verts=verts, skin=skin, cpu=s["animationCpuMs"], gpu=s["gpuMs"], tris=s["trianglesDrawn"],
                     device=s["device"], bounds=s.get("skinBounds", "joints"),
                     culled=s["frustumCulled"] + s["occlusionCulled"] + s.get("subpixelCulled", 0),
                     pos=k.get("maxPositionError"), nrm=k.get("maxNormalError"), outside=k.get("outside"),
                     ratio=k.get("meanRadiusRatio"), checked=k.get("instances", 0)))
rows.sort(key=lambda r: (r["n"], r["bounds"] != "joints"))


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


if rows:
    print(f"Device: {rows[0]['device']}\n")
    print("| instances | bounds | skinned vertices | skin pass ms | ns / vertex | poses CPU ms | us / instance (GPU + CPU) "
          "| max position error / radius | max normal error | frame GPU ms | objects culled | triangles drawn "
          "| vertices outside bounds | radius / tightest |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['n']:,} | {r['bounds']} | {r['verts']:,} | {r['skin']:.3f} | {1e6 * r['skin'] / r['verts']:.3f} "
              f"| {r['cpu']:.2f} | {1e3 * (r['skin'] + r['cpu']) / r['n']:.3f} | {fmt(r['pos'], '.1e')} "
              f"| {fmt(r['nrm'], '.1e')} | {r['gpu']:.2f} | {r['culled']:,} | {r['tris']:,} "
              f"| {fmt(r['outside'], ',')} of {r['checked']} instances | {fmt(r['ratio'], '.3f')} |")


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
