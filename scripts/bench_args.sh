# Sourced by the bench scripts: their common options. Set the defaults first (device, frames, out, counts), then
#   source scripts/bench_args.sh "$@"
# --device cpu|gpu, --frames N, --counts "N ...", and one positional argument: the output folder.
while (($#)); do
  case "$1" in
    --device) device=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --counts) counts=$2; shift 2 ;;
    *) out=$1; shift ;;
  esac
done
bin=${VISBUF_BIN:-build/tools/visbuf}
mkdir -p "$out"
