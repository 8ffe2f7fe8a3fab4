#!/usr/bin/env bash
# The main job on the bundled examples: installs dependencies if missing, builds, and runs the
# pipeline on examples/. Today the pipeline is: read and validate every example mesh, dissect
# each into quad patches, render the patch layouts to a PNG, then dissect the cat and the koala
# together (one set of common patches) and remesh the pair at uniform level 4 and adaptively.
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
echo "== qs-dissect examples/cat_16k.obj examples/koala_7k.obj (one common dissection)"
build/tools/qs-dissect examples/cat_16k.obj examples/koala_7k.obj -o "$out/cat_koala.dissection"
echo "== qs-remesh (uniform level 4, then adaptive 0.0025)"
build/tools/qs-remesh "$out/cat_koala.dissection" --level 4 -o "$out/cat_koala.remesh-L4"
build/tools/qs-remesh "$out/cat_koala.dissection" --adaptive 0.0025 -o "$out/cat_koala.remesh-adaptive"
build/tools/qs-render "$out/cat_koala.dissection/cat_16k.chart.ply" "$out/cat_koala.dissection/koala_7k.chart.ply" \
  "$out/cat_koala.remesh-L4/cat_16k.obj" "$out/cat_koala.remesh-L4/koala_7k.obj" \
  -o "$out/cat_koala.png" --patch-edges --wireframe --size 400
echo "== wrote $out/cat_koala.png (common patches and the level-4 remeshes with one connectivity)"
