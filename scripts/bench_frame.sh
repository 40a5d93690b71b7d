#!/usr/bin/env bash
# The end-to-end frame benchmark of docs/benchmarks.md: visbuf vs the forward reference on `field`
# with the peer's kitten mesh, 100k and 1M objects, 1024x768 and 1920x1080, plus the default scene and
# `city`. Each run renders 1 warm-up + N-1 measured frames per path (medians) and reports the error of
# visbuf against the forward path beside the times.
# Usage: scripts/bench_frame.sh [--device cpu|gpu] [--frames N] [OUTDIR]   (default OUTDIR: bench-out)
set -euo pipefail
cd "$(dirname "$0")/.."
device=cpu frames=3 out=bench-out
source scripts/bench_args.sh "$@"
kitten=${VISBUF_KITTEN:-assets/Kitten/kitten.glb}
run() {
  local name=$1; shift
  echo "== $name: visbuf render --device $device --frames $frames $*" | tee "$out/$name.txt"
  "$bin" render --device "$device" -o "" --frames "$frames" --json "$out/$name.json" "$@" 2>&1 | grep -v '^  \[' | tee -a "$out/$name.txt"
}
run default
run city --scene city --objects 100000 --reference
for n in 100000 1000000; do
  for size in 1024x768 1920x1080; do
    run "kitten_${n}_${size}" --mesh "$kitten" --objects "$n" --size "$size" --reference
  done
done
python3 scripts/bench_table.py "$out"/*.json | tee "$out/table.md"
