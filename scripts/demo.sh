#!/usr/bin/env bash
# Command (a): set up, build, and render the built-in default scene headless (lavapipe unless a GPU is
# present), writing visbuf.png + visbuf.json and printing per-pass GPU times and culling stats.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/tools/visbuf render --frames 3 -o visbuf.png --json visbuf.json "$@"
