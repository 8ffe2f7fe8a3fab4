#!/usr/bin/env bash
# Bodies with long limbs: the registered human pair with one mesh re-tessellated,
# seeds at the middle finger tips or the thumbs and the big toes (features: nose, head top, heels),
# and polygirl_20k alone; each dissected with qs-dissect at the default options, then its leaves
# summarized (bench/leafstats.py: patches, leaves over tau, the largest over-tau leaf's share of
# the surface) and its layout rendered (qs-render --patch-edges).
#
#   usage: bench/bodies.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-bodies)
#   env:   QS_TOOLS (default build/tools); extra qs-dissect options in QS_DISSECT_ARGS
#
# Writes OUT_DIR/{human-middle,human-thumbs,polygirl}/ (dissections) and OUT_DIR/*.png.
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-bodies}
TOOLS=${QS_TOOLS:-build/tools}
LM=bench/correspondence/smpl.landmarks.json
read -r -a EXTRA <<< "${QS_DISSECT_ARGS:-}"
for f in smpl_man_14k.obj smpl_woman_14k.obj polygirl_20k.off; do
  [ -f "$MESHES/$f" ] || { echo "bodies.sh: $MESHES/$f not found" >&2; exit 3; }
done
mkdir -p "$OUT"
# The thumbs variant: SMPL vertex ids 2729 and 6191 instead of the middle finger tips.
python3 - "$LM" "$OUT/smpl_thumbs.landmarks.json" <<'PY' || exit 1
import json, sys
d = json.load(open(sys.argv[1]))
d["seeds"] = [2729, 6191] + d["seeds"][2:]
json.dump(d, open(sys.argv[2], "w"), indent=1)
PY
"$TOOLS/qs-family" retessellate "$MESHES/smpl_woman_14k.obj" --landmarks "$LM" \
    -o "$OUT/smpl_woman_14k_r.obj" --quiet || exit 1
"$TOOLS/qs-family" retessellate "$MESHES/smpl_woman_14k.obj" --landmarks "$OUT/smpl_thumbs.landmarks.json" \
    -o "$OUT/smpl_woman_14k_rt.obj" --quiet || exit 1

# dissect NAME MESH... -- LANDMARKS...
dissect() {
  local name=$1; shift
  local meshes=() lms=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do meshes+=("$1"); shift; done
  [ $# -gt 0 ] && shift
  lms=("$@")
  local lmargs=()
  [ ${#lms[@]} -gt 0 ] && lmargs=(--landmarks "${lms[@]}")
  local t0 t1 rc
  t0=$(date +%s.%N)
  "$TOOLS/qs-dissect" "${meshes[@]}" "${lmargs[@]}" "${EXTRA[@]}" -o "$OUT/$name" --quiet \
      --report "$OUT/$name.report.txt" > "$OUT/$name.log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  echo "== $name: qs-dissect exit $rc, $(python3 -c "print(f'{$t1-$t0:.2f}')") s (wall clock)"
  [ -f "$OUT/$name/dissection.json" ] && /usr/bin/python3 bench/leafstats.py "$OUT/$name" --top 3
}
dissect human-middle "$MESHES/smpl_man_14k.obj" "$OUT/smpl_woman_14k_r.obj" -- "$LM" "$OUT/smpl_woman_14k_r.landmarks.json"
dissect human-thumbs "$MESHES/smpl_man_14k.obj" "$OUT/smpl_woman_14k_rt.obj" -- \
    "$OUT/smpl_thumbs.landmarks.json" "$OUT/smpl_woman_14k_rt.landmarks.json"
dissect polygirl "$MESHES/polygirl_20k.off" --

R="$TOOLS/qs-render"
[ -f "$OUT/human-middle/dissection.json" ] && "$R" "$OUT/human-middle/smpl_man_14k.chart.ply" \
    "$OUT/human-middle/smpl_woman_14k_r.chart.ply" -o "$OUT/human_pair_patches.png" --size 500x500 --patch-edges \
    --view 0,0,1 --up 0,1,0
[ -f "$OUT/human-thumbs/dissection.json" ] && "$R" "$OUT/human-thumbs/smpl_man_14k.chart.ply" \
    "$OUT/human-thumbs/smpl_woman_14k_rt.chart.ply" -o "$OUT/human_pair_thumbs_patches.png" --size 500x500 \
    --patch-edges --view 0,0,1 --up 0,1,0
[ -f "$OUT/polygirl/dissection.json" ] && "$R" "$OUT/polygirl/polygirl_20k.chart.ply" \
    "$OUT/polygirl/polygirl_20k.chart.ply" -o "$OUT/polygirl_patches.png" --size 500x400 --patch-edges \
    --view 1,1,1,-1,-1,-1
echo "renders: $OUT/*.png"
