#!/usr/bin/env bash
# The "MSAA" benchmark of docs/benchmarks.md: visbuf (multisampled IDs, per-sample shading at edges) and forward
# (hardware resolve) at 1x and the device's MSAA counts, on city (10,000 objects: many silhouettes) and
# DamagedHelmet (textured), frustum + occlusion culling, LOD 1 px; each row's error is against the forward path
# with no culling and no LOD at the same sample count. Then the table (scripts/msaa_table.py).
# Usage: scripts/msaa_bench.sh [--device cpu|gpu] [--msaa 1,4] [--size 1280x720] [OUTDIR]   (default OUTDIR: msaa-bench)
# VISBUF_BIN and VISBUF_HELMET override the program and the helmet's path (a self-contained GPU bundle).
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu out=msaa-bench msaa=1,4 size=1280x720
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    --msaa) msaa=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
# The textured asset: DamagedHelmet (the figures in docs/benchmarks.md) from the larger corpus when it is there,
# else the repository's NormalTangentMirrorTest (base colour, normal and ORM maps). The tables name the file.
helmet=${VISBUF_HELMET:-../shared/assets/DamagedHelmet/glTF-Binary/DamagedHelmet.glb}
[ -f "$helmet" ] || helmet=assets/NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf
echo "textured asset: $helmet"
frames="--warmup 1 --frames 3"                         # lavapipe: seconds per 4x frame
[ "$device" = cpu ] || frames="--warmup 3 --frames 10"
mkdir -p "$out"
"$bin" bench --device "$device" --scene city --objects 10000 --size "$size" --paths visbuf,forward \
  --cull frustum,occlusion --lod 1 --msaa "$msaa" $frames -o "$out/city_$size"
"$bin" bench --device "$device" --scene "$helmet" --size "$size" --paths visbuf,forward \
  --cull frustum,occlusion --lod 1 --msaa "$msaa" $frames -o "$out/helmet_$size"
if command -v python3 >/dev/null; then
  python3 scripts/msaa_table.py "$out"/city_*/bench.json "$out"/helmet_*/bench.json | tee "$out/table.md"
fi
