#!/usr/bin/env bash
# glTF conformance: scripts/conformance.sh DIR [--out TABLE.md] [--json ROWS.json] [--min-psnr DB]
# Renders every .gltf/.glb under DIR through visbuf and the forward path (256x192, lavapipe unless a GPU is
# present), bakes it, renders the pack, and prints one Markdown row per file: result, PSNR of each render against
# forward, pack size, warnings. Files DIR/conformance-expect.txt lists as refusals must be refused with the given
# message; anything else that does not load, crashes, times out or falls below the PSNR bar fails (exit 1).
# Needs a built tree (scripts/setup.sh); CI runs it on assets/ (ctest: cli.conformance_assets).
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: scripts/conformance.sh DIR [--out TABLE.md] [--json ROWS.json] [--min-psnr DB]" >&2
  exit 2
fi
exec python3 "$(dirname "$0")/conformance.py" "$@"
