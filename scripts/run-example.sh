#!/usr/bin/env bash
# The main job on the bundled examples: installs dependencies if missing, builds, and runs the
# whole pipeline on the three quadrupeds of examples/ (spot_2k, cat_16k, koala_7k, with their
# landmark files): one common dissection -> uniform remesh -> normal-map bake -> morph, ending in
# a GLB with one morph target per shape that a viewer plays; next to it the exact morph spot -> cat
# (qs-merge: the merged embeddings; spot's own mesh at one end, the cat's own mesh, placed on spot
# by the similarity, at the other). Every GLB is checked with the
# Khronos glTF validator when it is installed.
#   usage: scripts/run-example.sh [OUTDIR]   (default out/example)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh  # build and run dependencies and the glTF validator only (not --dev)
# Only the tools this script runs (scripts/build.sh builds everything, tests and benchmarks too).
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target qs-inspect qs-dissect qs-remesh qs-bake qs-morph qs-merge qs-render
out=${1:-out/example}
tools=build/tools
meshes=(examples/spot_2k.obj examples/cat_16k.obj examples/koala_7k.obj)
mkdir -p "$out"

echo "== qs-inspect: read and validate the examples"
"$tools/qs-inspect" "${meshes[@]}"

echo "== qs-dissect: one common dissection (landmarks from examples/<stem>.landmarks.json)"
"$tools/qs-dissect" "${meshes[@]}" -o "$out/dissection" --report "$out/dissection-report.txt"

echo "== qs-remesh: level 4 (even remesh, anisotropic cells), one connectivity for the three shapes"
"$tools/qs-remesh" "$out/dissection" --level 4 --error -o "$out/remesh-L4"

echo "== qs-bake: 128x128 normal-map tiles per patch, tangent space, OpenGL green"
"$tools/qs-bake" "$out/remesh-L4" --size 128 -o "$out/bake"

echo "== qs-morph: spot -> cat -> koala -> spot (cat and koala placed on spot by a similarity), 60 frames + GLB"
"$tools/qs-morph" "$out/remesh-L4" --path spot_2k,cat_16k,koala_7k,spot_2k --frames 60 \
  --align similarity --bake "$out/bake" --glb "$out/quadrupeds-morph.glb" -o "$out/morph"

echo "== qs-merge: the exact morph spot -> cat (the two meshes' embeddings overlaid: it starts and ends on the input meshes)"
"$tools/qs-merge" "$out/dissection" --pair spot_2k,cat_16k -o "$out/merge-spot-cat"
"$tools/qs-morph" "$out/merge-spot-cat" --frames 11 --align similarity --glb "$out/spot-cat-exact-morph.glb" \
  -o "$out/morph-exact"

echo "== glTF validator"
status=0
bash scripts/validate-gltf.sh "$out"/bake/*.glb "$out/quadrupeds-morph.glb" "$out/spot-cat-exact-morph.glb" || status=$?
if [ "$status" -eq 3 ]; then
  echo "(validator not installed: GLBs not validated)"
elif [ "$status" -ne 0 ]; then
  exit "$status"
fi

echo "== qs-render: patches and remeshes"
"$tools/qs-render" "$out"/dissection/*.chart.ply --patch-edges --size 400 -o "$out/patches.png"
"$tools/qs-render" "$out"/remesh-L4/*.obj --wireframe --size 400 -o "$out/remesh-L4.png"

echo
echo "Done. Open $out/quadrupeds-morph.glb in a glTF viewer (Blender, three.js editor, Godot):"
echo "its shape keys / morph targets are the three animals, and its animation plays the path."
