#!/usr/bin/env python3
"""Markdown table from `visbuf render --json` files (with --reference: forward path and error)."""
import json
import sys


def ms(v):
    return f"{v:,.1f}" if v >= 10 else f"{v:.2f}"


rows = []
for path in sys.argv[1:]:
    with open(path) as f:
        j = json.load(f)
    p = j["passMs"]
    ref = j.get("reference")
    vis_ms = j["gpuMs"] + j["cpuRecordMs"]
    row = [
        path.rsplit("/", 1)[-1].removesuffix(".json"),
        f'{j["width"]}x{j["height"]}',
        f'{j["objects"]:,}',
        f'{j["drawsRendered"]:,}',
        f'{j["trianglesDrawn"]:,}',
        ms(sum(v for k, v in p.items() if k.startswith("cull"))),
        ms(sum(v for k, v in p.items() if k.startswith("raster") or k == "visibility")),
        ms(p.get("shade", 0)),
        ms(vis_ms),
    ]
    if ref:
        fwd_ms = ref["gpuMs"] + ref["cpuRecordMs"]
        e = ref["error"]
        row += [f'{ms(fwd_ms)} ({ref.get("kind", "forward")})', f"{fwd_ms / vis_ms:.2f}x",
                f'{e["psnr"]:.1f} / {e["maxAbs"]:.4f}']
    else:
        row += ["", "", ""]
    rows.append(row)

head = ["config", "size", "objects", "drawn", "triangles", "cull ms", "raster ms", "shade ms",
        "visbuf frame ms", "reference frame ms", "reference/visbuf", "PSNR dB / max err vs reference"]
print("| " + " | ".join(head) + " |")
print("|" + "---|" * len(head))
for r in rows:
    print("| " + " | ".join(r) + " |")
