#!/usr/bin/env python3
"""Markdown table of scripts/bench_lights.sh's JSON files: per-pass GPU medians per light configuration and
the error of the tiled shading against every light at every pixel."""
import json
import sys
from pathlib import Path

out = Path(sys.argv[1])
counts = sys.argv[2:]
rows = [("none (ambient only)", "time_none", None), ("directional only", "time_sun", None)]
rows += [(f"directional + {int(n):,} point", f"time_{n}", f"error_{n}") for n in counts]
passes = ["cull early", "raster early", "depth pyramid", "cull late", "raster late", "light cull", "shade"]
print("| lights | " + " | ".join(passes) + " | GPU total | lights / tile (mean, max) | overflow tiles | "
      "error vs all lights (max, PSNR, at size) | every-light frame GPU ms |")
print("|" + "---|" * (len(passes) + 6))
for name, timing, error in rows:
    t = json.loads((out / f"{timing}.json").read_text())
    ms = lambda v: f"{v:.3f}" if v < 10 else f"{v:.0f}"  # GPU: 3 decimals; lavapipe: whole ms
    cells = [ms(t["passMs"][p]) if p in t["passMs"] else "-" for p in passes]
    light = t["lights"]
    tiles = f"{light['meanPerTile']:.1f}, {light['maxPerTile']}" if light["culled"] else "-"
    overflow = str(light["tileOverflow"]) if light["culled"] else "-"
    err = "- (nothing to cull)"
    refMs = "-"
    if error:
        e = json.loads((out / f"{error}.json").read_text())
        r = e["reference"]["error"]
        psnr = "inf" if r["psnr"] >= 999 else f"{r['psnr']:.1f} dB"
        err = f"{r['maxAbs']:.2g}, {psnr}, {e['width']}x{e['height']}"
        refMs = ms(e["reference"]["gpuMs"])
    print(f"| {name} | " + " | ".join(cells) + f" | {ms(t['gpuMs'])} | {tiles} | {overflow} | {err} | {refMs} |")
