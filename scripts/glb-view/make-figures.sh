#!/usr/bin/env bash
# Regenerates the README figures in docs/images/ with scripts/glb-view.sh (three.js in headless
# Chromium), from the repository root:   bash scripts/glb-view/make-figures.sh [WORKDIR]
#   head_normal_map.png            paper fig. 19: max_planck_11k original (angle-weighted vertex
#                                  normals, the field qs-bake samples) | level 3 without its
#                                  normal map | level 3 with it (dissect --max-area 0.15, remesh
#                                  --level 3, bake --size 256; the work goes to WORKDIR)
#   morph_strip_common_scale.png   out/example/quadrupeds-morph.glb at morph weights (cat, koala) =
#                                  (0,0) (0.5,0) (1,0) (0.5,0.5) (0,1), one framing for all
# Needs the built tools (scripts/build.sh) and out/example (scripts/run-example.sh).
set -euo pipefail
cd "$(dirname "$0")/../.."
work=${1:-$(mktemp -d /tmp/qs-figures.XXXXXX)}
tools=build/tools
view=scripts/glb-view.sh
cat=(node scripts/glb-view/pngcat.mjs)
img=docs/images
mkdir -p "$work" "$img"

head=${QS_HEAD_MESH:-../shared/meshes/max_planck_11k.obj}
"$tools/qs-dissect" "$head" --max-area 0.15 -o "$work/head-dissection" -q
"$tools/qs-remesh" "$work/head-dissection" --level 3 -o "$work/head-L3" -q
"$tools/qs-bake" "$work/head-L3" --size 256 -o "$work/head-bake" -q
glb="$work/head-bake/$(basename "${head%.*}").glb"
v=0.7,0.2,-1
"$view" "$head" -o "$work/h1.png" --size 360x420 --view $v --angle-normals --label "original (10.5k triangles)" -q
"$view" "$glb" -o "$work/h2.png" --size 360x420 --view $v --no-map --label "level 3 (2.3k triangles), no map" -q
"$view" "$glb" -o "$work/h3.png" --size 360x420 --view $v --label "level 3 + its normal map" -q
"${cat[@]}" -o "$img/head_normal_map.png" "$work"/h1.png "$work"/h2.png "$work"/h3.png

morph=out/example/quadrupeds-morph.glb
weights=(0,0 0.5,0 1,0 0.5,0.5 0,1)
labels=("spot (0, 0)" "(0.5, 0)" "cat (1, 0)" "(0.5, 0.5)" "koala (0, 1)")
for fit in all; do
  frames=()
  for i in "${!weights[@]}"; do
    "$view" "$morph" -o "$work/m-$fit-$i.png" --size 240x240 --view -1,0.5,-1 \
      --weights "${weights[$i]}" --fit $fit --label "${labels[$i]}" -q
    frames+=("$work/m-$fit-$i.png")
  done
  name=morph_strip_common_scale
  "${cat[@]}" -o "$img/$name.png" "${frames[@]}"
done
ls -l "$img"/head_normal_map.png "$img"/morph_strip_common_scale.png
