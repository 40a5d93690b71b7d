#!/usr/bin/env bash
# The asset pictures of docs/assets.md: each named asset of assets/ rendered by visbuf and by the
# forward reference (same camera: the scene's default, framing its bounds), with the error between them.
# Skinned assets are posed at the time given. Usage: scripts/asset_images.sh [OUTDIR] (default docs/images/assets)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/images/assets}
bin=${VISBUF_BIN:-build/tools/visbuf}
assets=${VISBUF_ASSETS:-assets}
mkdir -p "$out"
while read -r name file time; do
  for path in visbuf forward; do
    "$bin" render --scene "$assets/$file" --device cpu --validation --size 384x384 --no-lod --time "$time" \
      --path "$path" -o "$out/${name}_$path.png" > "$out/${name}_$path.txt" 2>&1
  done
  "$bin" render --scene "$assets/$file" --device cpu --validation --size 384x384 --no-lod --time "$time" \
    --reference -o "" 2>&1 | grep -E '^error' | sed "s/^/$name (t = $time s): /"
  rm -f "$out/${name}_visbuf.txt" "$out/${name}_forward.txt"
done <<'LIST'
DamagedHelmet DamagedHelmet/glTF-Binary/DamagedHelmet.glb 0
AlphaBlendModeTest AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf 0
OrientationTest OrientationTest/glTF/OrientationTest.gltf 0
MultiUVTest MultiUVTest/glTF/MultiUVTest.gltf 0
Fox Fox/glTF-Binary/Fox.glb 1.3
CesiumMan CesiumMan/glTF/CesiumMan.gltf 1.0
RiggedFigure RiggedFigure/glTF/RiggedFigure.gltf 0.5
LIST
