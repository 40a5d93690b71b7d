#!/usr/bin/env bash
# Lighting cost (docs/benchmarks.md, "Lights"): the same generated field (10,000 torus knots, camera inside
# the field) with no light at all (--no-sun: ambient + emissive), the directional light only, and N scattered
# point lights (tiled light culling), at 1920x1080; medians over the frames after the first. Then the error of
# the tiled shading against every light at every pixel (--reference-lights): at 1080p for the smaller counts,
# at 640x360 above VISBUF_REF_FULL_MAX (default 10000) lights: the all-lights reference costs N lights per
# pixel (10,000 lights at 1080p: ~4 min on lavapipe).
# Usage: scripts/bench_lights.sh [--device cpu|gpu] [--frames N] [--counts "1000 10000"] [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu frames=5 out=bench-lights counts="1000 10000"
source scripts/bench_args.sh "$@"
refmax=${VISBUF_REF_FULL_MAX:-10000}
scene=(--device "$device" -o "" --scene field --objects 10000 --camera-pos 0,0,250)
"$bin" render "${scene[@]}" --size 1920x1080 --frames "$frames" --no-sun --json "$out/time_none.json" > "$out/time_none.txt"
"$bin" render "${scene[@]}" --size 1920x1080 --frames "$frames" --json "$out/time_sun.json" > "$out/time_sun.txt"
for n in $counts; do
  "$bin" render "${scene[@]}" --size 1920x1080 --frames "$frames" --lights "$n" --json "$out/time_$n.json" > "$out/time_$n.txt"
  size=1920x1080
  if [ "$n" -gt "$refmax" ]; then size=640x360; fi
  "$bin" render "${scene[@]}" --size "$size" --frames 1 --lights "$n" --reference-lights --json "$out/error_$n.json" > "$out/error_$n.txt"
done
python3 scripts/lights_table.py "$out" $counts | tee "$out/table.md"
