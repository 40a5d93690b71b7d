#!/usr/bin/env bash
# The "Visibility buffer vs G-buffer" benchmark of docs/benchmarks.md: visbuf, gbuffer and forward on city
# (10,000 objects, bench's avenue walk) and DamagedHelmet (orbit), at 1920x1080 and 3840x2160, frustum and
# occlusion culling, LOD 1 px; then the table (scripts/gbuffer_table.py).
# Usage: scripts/gbuffer_bench.sh [--device cpu|gpu] [OUTDIR]     (default OUTDIR: gbuffer-bench)
# VISBUF_BIN and VISBUF_HELMET override the program and the helmet's path (a self-contained GPU bundle).
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu out=gbuffer-bench
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
helmet=${VISBUF_HELMET:-../shared/assets/DamagedHelmet/glTF-Binary/DamagedHelmet.glb}
frames="--warmup 2 --frames 5"                         # lavapipe: seconds per frame at 4K
[ "$device" = cpu ] || frames="--warmup 3 --frames 10"
mkdir -p "$out"
for size in 1920x1080 3840x2160; do
  "$bin" bench --device "$device" --scene city --objects 10000 --size $size --paths visbuf,gbuffer,forward \
    --cull frustum,occlusion --lod 1 $frames -o "$out/city_$size"
  "$bin" bench --device "$device" --scene "$helmet" --size $size --paths visbuf,gbuffer,forward \
    --cull frustum,occlusion --lod 1 $frames -o "$out/helmet_$size"
done
python3 scripts/gbuffer_table.py "$out"/city_*/bench.json "$out"/helmet_*/bench.json | tee "$out/table.md"
