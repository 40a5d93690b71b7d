#!/usr/bin/env python3
"""Markdown table "visbuf vs G-buffer vs forward" from `visbuf bench` outputs (bench.json, one per scene and size).

Per row: passes grouped as cull (both phases), pyramid, raster (visibility / gbuffer / forward, both phases),
classify (material classification: count, scan, scatter) and resolve (shade / lighting), medians in ms; visbuf rows
name their shading mode (uber / classified) and, classified, the materials present; frame median and p95; raster writes and bytes written per pixel at the
last camera (countOverdraw frame); error vs the bench's reference (forward, no culling, no LOD).
Usage: scripts/gbuffer_table.py OUT1/bench.json OUT2/bench.json ...
"""
import json
import sys

from table_util import group, ms


print("| scene | size | path | cull | triangles | cull ms | pyramid ms | raster ms | classify ms | resolve ms "
      "| frame ms (p95) | raster writes/px | B/px targets | B/px written | PSNR dB / max err vs reference |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for path in sys.argv[1:]:
    with open(path) as f:
        j = json.load(f)
    scene = j["scene"].rsplit("/", 1)[-1]
    for r in j["rows"]:
        p = r["passMs"]
        objects = f' {r["objects"]:,}' if r["objects"] else ""
        psnr = r["error"]["psnrMean"]
        psnr = psnr if isinstance(psnr, str) else f"{psnr:.1f}"
        path = r["path"]
        if r.get("shading", "-") != "-":
            present = f', {r["materialsPresent"]:.0f} mat.' if "materialsPresent" in r else ""
            path += f' ({r["shading"]}{present})'
        materials = f' ({j["materials"]} mat.)' if j.get("materials") else ""
        print(f'| {scene}{objects}{materials} | {j["width"]}x{j["height"]} | {path} | {r["cull"]} | '
              f'{r["trianglesDrawn"]:,.0f} | {ms(group(p, ["cull"]))} | {ms(group(p, ["depth pyramid"]))} | '
              f'{ms(group(p, ["visibility", "raster", "gbuffer", "forward"]))} | {ms(group(p, ["classify"]))} | '
              f'{ms(group(p, ["shade", "lighting"]))} | {ms(r["frameMs"]["median"])} ({ms(r["frameMs"]["p95"])}) | '
              f'{r["rasterWritesPerPixel"]:.2f} | {r["targetBytesPerPixel"]} | {r["bytesWrittenPerPixel"]:.1f} | '
              f'{psnr} / {r["error"]["maxAbs"]:.4f} |')
