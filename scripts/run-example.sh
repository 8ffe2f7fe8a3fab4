#!/usr/bin/env bash
# The main job on the bundled examples: installs dependencies if missing, builds, and runs the
# pipeline on examples/. Today the pipeline is: read and validate every example mesh, dissect
# each into quad patches, and render the patch layouts to a PNG.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
out=${1:-out/example}
mkdir -p "$out"
echo "== qs-inspect examples/*.obj"
build/tools/qs-inspect examples/*.obj
build/tools/qs-inspect --json examples/*.obj > "$out/inspect.json"
echo "== wrote $out/inspect.json"
charts=()
for mesh in examples/*.obj; do
  stem=$(basename "$mesh" .obj)
  echo "== qs-dissect $mesh"
  build/tools/qs-dissect "$mesh" -o "$out/$stem.dissection"
  charts+=("$out/$stem.dissection/$stem.chart.ply")
done
build/tools/qs-render "${charts[@]}" -o "$out/charts.png" --patch-edges --size 400
echo "== wrote $out/charts.png (the patch layouts, side by side)"
