#!/usr/bin/env bash
# Command (a): set up, build, and render the demo scene headless (lavapipe unless a GPU is present), writing
# visbuf.png + visbuf.json and printing per-pass GPU times and culling stats. The demo scene is what visbuf is
# for: 100,000 kittens (assets/Kitten, 2.9 billion triangles at full detail) scattered in a 600-unit cube, seen
# from its centre in the peer's view (niagara's: +z, 70 degree field of view, near plane 0.5); LOD, occlusion
# culling and the micro-raster bring it to a few million triangles drawn. Extra arguments are added to render's
# (e.g. `--device gpu`, `--size 1024x768`).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/tools/visbuf render --scene field --mesh assets/Kitten/kitten.glb --objects 100000 \
  --camera-pos 0,0,0 --camera-target 0,0,1 --fov 70 --near 0.5 --frames 3 -o visbuf.png --json visbuf.json "$@"
