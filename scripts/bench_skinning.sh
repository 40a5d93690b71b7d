#!/usr/bin/env bash
# Skinning cost (docs/benchmarks.md, "Animated meshes"): N animated Foxes (assets/Fox, 1,502 skinned
# vertices each after welding, every instance at its own phase) at 1k, 10k and 100k instances, 1280x720, the
# animation advancing every frame (--animate), medians over the frames after the first, each run with the
# joint-reach bounds and with the GPU-reduced bounds (--skin-bounds), and --skin-check 64: 64 instances read
# back after the last frame against the CPU's double-precision skinning and their bounds. Then the static-scene check:
# the same static field rendered by this binary (skinning code present, skipped) and, when VISBUF_BASELINE
# names a binary built without skinning, by that one, alternating runs.
# Usage: scripts/bench_skinning.sh [--device cpu|gpu] [--frames N] [--counts "1000 10000"] [--bounds "joints gpu"]
#        [--no-static] [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
nostatic=0 device=cpu frames=4 out=bench-skin counts="1000 10000 100000" bounds="joints gpu"
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --counts) counts=$2; shift 2 ;;
    --bounds) bounds=$2; shift 2 ;;
    --no-static) nostatic=1; shift ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
fox=${VISBUF_FOX:-assets/Fox/glTF-Binary/Fox.glb}
mkdir -p "$out"
for n in $counts; do
  for b in $bounds; do
    "$bin" render --device "$device" -o "" --frames "$frames" --animate --size 1280x720 --scene "$fox" \
      --instances "$n" --skin-bounds "$b" --skin-check 64 --json "$out/fox_${n}_$b.json" > "$out/fox_${n}_$b.txt" 2>&1 ||
      echo "fox x $n ($b bounds): failed (see $out/fox_${n}_$b.txt)"
  done
done
[ "$nostatic" = 1 ] && { python3 scripts/skinning_table.py "$out" | tee "$out/table.md"; exit 0; }
static_args=(--device "$device" -o "" --frames "$frames" --size 1280x720 --scene field --objects 100000)
for round in 1 2 3; do
  "$bin" render "${static_args[@]}" --json "$out/static_with_$round.json" > /dev/null 2>&1
  if [ -n "${VISBUF_BASELINE:-}" ]; then
    "$VISBUF_BASELINE" render "${static_args[@]}" --json "$out/static_without_$round.json" > /dev/null 2>&1
  fi
done
python3 scripts/skinning_table.py "$out" | tee "$out/table.md"
