#!/usr/bin/env python3
"""Markdown table "MSAA: 1x vs 2x/4x" from `visbuf bench --msaa ...` outputs (bench.json, one per scene and size).

Per row: raster (both phases) and resolve (shade) medians in ms, frame median and p95, bytes per pixel of the
targets, the pixels that took visbuf's per-sample path (median over the measured frames, % of all pixels), and
the error against the bench's reference at the same sample count (forward with no culling and no LOD, hardware
resolve): PSNR over all measured frames / max error / share of pixels off by more than 1/255.
Usage: scripts/msaa_table.py OUT1/bench.json OUT2/bench.json ...
"""
import json
import sys

from table_util import group, ms


print("| scene | size | path | msaa | cull | raster ms | shade ms | frame ms (p95) | B/px targets | per-sample px "
      "| PSNR dB / max err / px > 1/255 vs forward same msaa |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for path in sys.argv[1:]:
    with open(path) as f:
        j = json.load(f)
    scene = j["scene"].rsplit("/", 1)[-1]
    pixels = j["width"] * j["height"]
    for r in sorted(j["rows"], key=lambda r: (r["path"], r["cull"], r["msaa"])):
        p = r["passMs"]
        objects = f' {r["objects"]:,}' if r["objects"] else ""
        psnr = r["error"]["psnrMean"]
        psnr = psnr if isinstance(psnr, str) else f"{psnr:.1f}"
        per = (f'{r["perSamplePixels"]:,.0f} ({100.0 * r["perSamplePixels"] / pixels:.1f}%)'
               if r["path"] == "visbuf" and r["msaa"] > 1 else "-")
        print(f'| {scene}{objects} | {j["width"]}x{j["height"]} | {r["path"]} | {r["msaa"]}x | {r["cull"]} | '
              f'{ms(group(p, ["visibility", "raster", "forward"]))} | {ms(group(p, ["shade"]))} | '
              f'{ms(r["frameMs"]["median"])} ({ms(r["frameMs"]["p95"])}) | {r["targetBytesPerPixel"]} | {per} | '
              f'{psnr} / {r["error"]["maxAbs"]:.4f} / {100.0 * r["error"]["differingFraction"]:.2f}% |')
