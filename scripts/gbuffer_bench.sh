#!/usr/bin/env bash
# The "Visibility buffer vs G-buffer vs forward" benchmarks of docs/benchmarks.md, then their table
# (scripts/gbuffer_table.py).
#   untextured (default): visbuf, gbuffer and forward on city (10,000 objects, bench's avenue walk) and DamagedHelmet
#     (orbit), at 1920x1080 and 3840x2160, frustum and occlusion culling, LOD 1 px.
#   --textured: the same paths with textures, visbuf with both shading modes (ubershader, material classification),
#     frustum culling, LOD 1 px, on an overdraw-heavy many-material scene (foliage-opaque: CARDS double-sided cards
#     with 256 generated PBR materials, 3 of 4 textured) and the low-overdraw DamagedHelmet (one textured material;
#     VISBUF_HELMET may name a pack baked from it, as the GPU bundle does: the GPU build has no image decoder).
# Usage: scripts/gbuffer_bench.sh [--device cpu|gpu] [--textured] [OUTDIR]     (default OUTDIR: gbuffer-bench)
# VISBUF_BIN and VISBUF_HELMET override the program and the helmet's path (a self-contained GPU bundle);
# CARDS: the foliage card count (default 40000: ~3.5 raster writes per pixel, and a lavapipe 4K run of the textured
# set stays within minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu out=gbuffer-bench textured=0
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    --textured) textured=1; shift ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
# The textured asset: DamagedHelmet (the figures in docs/benchmarks.md) from the larger corpus when it is there,
# else the repository's NormalTangentMirrorTest (base colour, normal and ORM maps). The tables name the file.
helmet=${VISBUF_HELMET:-../shared/assets/DamagedHelmet/glTF-Binary/DamagedHelmet.glb}
[ -f "$helmet" ] || helmet=assets/NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf
echo "textured asset: $helmet"
frames="--warmup 2 --frames 5"                         # lavapipe: seconds per frame at 4K
[ "$device" = cpu ] || frames="--warmup 3 --frames 10"
mkdir -p "$out"
if ((textured)); then
  [ "$device" = cpu ] && frames="--warmup 1 --frames 2"  # lavapipe: the 4K ubershader frame takes minutes
  for size in 1920x1080 3840x2160; do
    "$bin" bench --device "$device" --scene foliage-opaque --objects "${CARDS:-40000}" --materials 256 --size $size \
      --paths visbuf,gbuffer,forward --shading uber,classified --cull frustum --lod 1 $frames -o "$out/foliage_$size"
    "$bin" bench --device "$device" --scene "$helmet" --size $size --paths visbuf,gbuffer,forward \
      --shading uber,classified --cull frustum --lod 1 $frames -o "$out/helmet_$size"
  done
  python3 scripts/gbuffer_table.py "$out"/foliage_*/bench.json "$out"/helmet_*/bench.json | tee "$out/table.md"
  exit
fi
for size in 1920x1080 3840x2160; do
  "$bin" bench --device "$device" --scene city --objects 10000 --size $size --paths visbuf,gbuffer,forward \
    --cull frustum,occlusion --lod 1 $frames -o "$out/city_$size"
  "$bin" bench --device "$device" --scene "$helmet" --size $size --paths visbuf,gbuffer,forward \
    --cull frustum,occlusion --lod 1 $frames -o "$out/helmet_$size"
done
python3 scripts/gbuffer_table.py "$out"/city_*/bench.json "$out"/helmet_*/bench.json | tee "$out/table.md"
