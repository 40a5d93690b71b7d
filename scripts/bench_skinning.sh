#!/usr/bin/env bash
# Skinning cost (docs/benchmarks.md, "Animated meshes"): N animated Foxes (../shared/assets/Fox, 1,728 skinned
# vertices each, every instance at its own phase) at 1k, 10k and 100k instances, 1280x720, the animation
# advancing every frame (--animate), medians over the frames after the first. Then the static-scene check:
# the same static field rendered by this binary (skinning code present, skipped) and, when VISBUF_BASELINE
# names a binary built without skinning, by that one, alternating runs.
# Usage: scripts/bench_skinning.sh [--device cpu|gpu] [--frames N] [--counts "1000 10000"] [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu frames=4 out=bench-skin counts="1000 10000 50000 100000"
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --counts) counts=$2; shift 2 ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
fox=${VISBUF_FOX:-../shared/assets/Fox/glTF-Binary/Fox.glb}
mkdir -p "$out"
for n in $counts; do
  "$bin" render --device "$device" -o "" --frames "$frames" --animate --size 1280x720 --scene "$fox" \
    --instances "$n" --json "$out/fox_$n.json" > "$out/fox_$n.txt" 2>&1 || echo "fox x $n: failed (see $out/fox_$n.txt)"
done
static_args=(--device "$device" -o "" --frames "$frames" --size 1280x720 --scene field --objects 100000)
for round in 1 2 3; do
  "$bin" render "${static_args[@]}" --json "$out/static_with_$round.json" > /dev/null 2>&1
  if [ -n "${VISBUF_BASELINE:-}" ]; then
    "$VISBUF_BASELINE" render "${static_args[@]}" --json "$out/static_without_$round.json" > /dev/null 2>&1
  fi
done
python3 scripts/skinning_table.py "$out" | tee "$out/table.md"
