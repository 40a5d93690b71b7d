#!/usr/bin/env bash
# Runs libFuzzer targets of tests/fuzz under ASan + UBSan (+ LeakSanitizer):
#   scripts/fuzz.sh TARGET SECONDS          one target for a bounded time (CI), e.g. scripts/fuzz.sh fuzz_pack_reader 60
#   scripts/fuzz.sh --long [TARGET] [SECONDS]
#                                           long local runs: every target (or TARGET), SECONDS each (default 3600),
#                                           a new random seed each run, and a corpus that persists and grows in
#                                           build-clang/fuzz/TARGET-corpus/ (seeded from the committed one), so
#                                           successive runs go deeper; still stops at the first finding.
# TARGET: fuzz_gltf_import | fuzz_pack_reader | fuzz_image_decode | fuzz_mesh_build | fuzz_draco_decode.
#
# Configures and builds the clang build (build-clang/: clang, RelWithDebInfo, -Werror, ASan + UBSan, libFuzzer
# instrumentation; the same configuration as scripts/test.sh) when needed, then fuzzes a COPY of the committed
# seed corpus tests/fuzz/corpus/TARGET/ (new inputs are thrown away: the committed corpus never grows), with the
# target's dictionary when there is one. Prints the executions per second and the coverage reached (libFuzzer's
# final cov: / ft: and its -print_final_stats). Slow and hungry inputs are findings like crashes: exits non-zero
# on any crash, sanitizer report, leak, timeout (an input running past 20 s: -timeout=20) or out-of-memory
# (-rss_limit_mb=2048, and -malloc_limit_mb the same for one allocation); the input is kept in
# build-clang/fuzz/TARGET-artifacts/ and the report printed, the full log is build-clang/fuzz/TARGET.log.
# Reproduce a finding: build-clang/tests/fuzz/TARGET build-clang/fuzz/TARGET-artifacts/crash-... (or timeout-,
# oom-, slow-unit-).
# FUZZ_SEED=N fixes libFuzzer's random seed (scripts/test.sh uses 1, so that CI explores the same inputs on
# every run and a red run can be replayed); unset, every run explores from a new seed.
set -euo pipefail
cd "$(dirname "$0")/.."

targets=(fuzz_gltf_import fuzz_pack_reader fuzz_image_decode fuzz_mesh_build fuzz_draco_decode)
usage() {
  echo "usage: scripts/fuzz.sh TARGET SECONDS | scripts/fuzz.sh --long [TARGET] [SECONDS]" >&2
  echo "       TARGET: ${targets[*]}" >&2
  exit 2
}
if [ "${1:-}" = "--long" ]; then
  shift
  chosen=("${targets[@]}")
  if [ $# -ge 1 ] && [[ ! "$1" =~ ^[0-9]+$ ]]; then
    chosen=("$1")
    shift
  fi
  long_seconds=${1:-3600}
  [ $# -le 1 ] || usage
  for t in "${chosen[@]}"; do
    FUZZ_LONG=1 "$0" "$t" "$long_seconds" || exit 1
  done
  exit 0
fi
[ $# -eq 2 ] || usage
target=$1
seconds=$2
case "$target" in
  fuzz_gltf_import) max_len=32768 ;;   # the seeds are up to 15 KB (a skinned, animated GLB)
  fuzz_pack_reader) max_len=32768 ;;   # the seed packs are up to 17 KB
  fuzz_image_decode) max_len=8192 ;;   # tiny PNG / JPEG seeds; the pixel budget is in the target
  fuzz_mesh_build) max_len=8192 ;;     # raw meshes are repeated to 20k triangles; small glTF seeds
  fuzz_draco_decode) max_len=4096 ;;   # Draco streams of a few hundred bytes (make_draco_corpus.py)
  *) usage ;;
esac
[[ "$seconds" =~ ^[1-9][0-9]*$ ]] || usage

build=build-clang
out=$build/fuzz
mkdir -p "$out"
if ! CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVISBUF_WERROR=ON \
       -DVISBUF_SANITIZE=ON -DVISBUF_FUZZ=ON >"$out/configure.log" 2>&1; then
  cat "$out/configure.log" >&2
  exit 1
fi
cmake --build "$build" -j "$(nproc)" --target "$target"

if [ -n "${FUZZ_LONG:-}" ]; then
  # Long runs keep what they find: the corpus persists between runs (and never enters the repository).
  corpus=$out/$target-corpus
  mkdir -p "$corpus"
  cp -n tests/fuzz/corpus/"$target"/* "$corpus"/
  where="build-clang/fuzz/$target-corpus"
else
  corpus=$(mktemp -d "${TMPDIR:-/tmp}/visbuf-$target-corpus.XXXXXX")
  trap 'rm -rf "$corpus"' EXIT
  cp tests/fuzz/corpus/"$target"/* "$corpus"/
  where="a copy of tests/fuzz/corpus/$target"
fi
seeds=$(find "$corpus" -type f | wc -l)
dict=()
[ -f tests/fuzz/"$target".dict ] && dict=(-dict=tests/fuzz/"$target".dict)
artifacts=$out/$target-artifacts
mkdir -p "$artifacts"
log=$out/$target.log

echo "== $target: ${seconds}s on $where ($seeds inputs), log $log"
status=0
ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 \
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 LSAN_OPTIONS=print_suppressions=0 \
  "$build/tests/fuzz/$target" "$corpus" "${dict[@]}" -max_total_time="$seconds" -max_len="$max_len" \
  -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=20 -print_final_stats=1 -artifact_prefix="$artifacts/" ${FUZZ_SEED:+-seed="$FUZZ_SEED"} \
  >"$log" 2>&1 || status=$?

# libFuzzer's last status line (#N DONE cov: ... ft: ... corp: ... exec/s: ...) and final statistics.
grep -E '^#[0-9]+[[:space:]]+(DONE|INITED)' "$log" | tail -n 2 || true
grep -E '^stat::' "$log" || true
if [ "$status" -ne 0 ] || ! grep -qE '^#[0-9]+[[:space:]]+DONE' "$log"; then
  echo "== $target FAILED (exit $status): the report, from the log:" >&2
  grep -nE 'ERROR: |WARNING: |runtime error|deadly signal|fuzz contract violated|libFuzzer: ' "$log" | head -n 5 >&2 || true
  tail -n 60 "$log" >&2
  exit 1
fi
echo "== $target passed"
