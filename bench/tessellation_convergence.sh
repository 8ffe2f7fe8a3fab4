#!/usr/bin/env bash
# Tessellation convergence: does the common map of a surface and its own
# re-tessellation approach the identity as both get finer?
#
#   usage: bench/tessellation_convergence.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-convergence)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 100000), MULTIPLES (default "1 2 4 8"),
#          DISSECT_ARGS (extra qs-dissect options)
#
# For each surface S (smpl_man_14k with the benchmark's landmarks, and a generated shape) and each
# multiple m: A = S re-tessellated to m times its face count (vertices exactly on S), B = A
# re-tessellated again (exact (face, barycentric) origins on A), both dissected together with the
# same landmarks, and `qs-metro --correspondence` measures B's map against the exact identity.
# The ratio column is the mean error at m against the mean error at m = 1; "order" is the
# convergence order in the mean edge length h ~ 1 / sqrt(faces): log(ratio) / log(sqrt(1 / m)).
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-convergence}
TOOLS=${QS_TOOLS:-build/tools}
SAMPLES=${SAMPLES:-100000}
read -r -a MULT <<< "${MULTIPLES:-1 2 4 8}"
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
mkdir -p "$OUT"
RESULTS="$OUT/results.tsv"
: > "$RESULTS"

faces_of() { grep -c '^f ' "$1"; }

# run NAME MESH LANDMARKS
run() {
  local name=$1 mesh=$2 lm=$3 base
  base=$(faces_of "$mesh")
  for m in "${MULT[@]}"; do
    local d="$OUT/$name-x$m" t0 t1
    mkdir -p "$d"
    "$TOOLS/qs-family" retessellate "$mesh" --landmarks "$lm" --faces $((base * m)) -o "$d/a.obj" --quiet || exit 1
    "$TOOLS/qs-family" retessellate "$d/a.obj" --landmarks "$d/a.landmarks.json" -o "$d/b.obj" --quiet || exit 1
    t0=$(date +%s.%N)
    if ! "$TOOLS/qs-dissect" "$d/a.obj" "$d/b.obj" --landmarks "$d/a.landmarks.json" "$d/b.landmarks.json" \
        -o "$d/dissection" --quiet --report "$d/report.txt" "${EXTRA[@]}" > "$d/dissect.log" 2>&1; then
      echo "$name x$m: qs-dissect failed: $(tail -n1 "$d/dissect.log")"
      continue
    fi
    t1=$(date +%s.%N)
    "$TOOLS/qs-metro" --correspondence "$d/dissection" --map - "$d/b.map.json" --samples "$SAMPLES" --json \
        -o "$d/corr.json" > "$d/metro.log" 2>&1 || { echo "$name x$m: measuring failed: $(tail -n1 "$d/metro.log")"; continue; }
    printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$m" "$(faces_of "$d/a.obj")" "$(python3 -c "print(f'{$t1-$t0:.2f}')")" \
        "$d/corr.json" >> "$RESULTS"
    echo "$name x$m: measured"
  done
}

if [ -f "$MESHES/smpl_man_14k.obj" ]; then
  run smpl_man "$MESHES/smpl_man_14k.obj" bench/correspondence/smpl.landmarks.json
else
  echo "no smpl_man_14k in $MESHES: skipped"
fi
g="$OUT/generated"
"$TOOLS/qs-family" generate -n 1 --seed 1 --faces 8000 --quiet -o "$g" || exit 1
run generated "$g/shape00.obj" "$g/shape00.landmarks.json"

python3 - "$RESULTS" <<'PY'
import json, math, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print()
print("| surface | faces (A) | dissect + refine | patches | mean | p95 | max | corners (mean) | same patch | ratio to x1 | order |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
first = {}
for name, m, faces, secs, path in rows:
    doc = json.load(open(path)); p = doc["pairs"][0]; d = p["dissection"]
    first.setdefault(name, (int(m), d["mean_percent"]))
    m0, e0 = first[name]
    ratio = d["mean_percent"] / e0
    order = "" if int(m) == m0 else f"{math.log(ratio) / math.log(math.sqrt(m0 / int(m))):.2f}"
    print(f"| {name} x{m} | {faces} | {secs} s | {doc['patches']} | {d['mean_percent']:.3f}% | {d['p95_percent']:.2f}% | "
          f"{d['max_percent']:.2f}% | {p['corner_distance_mean_percent']:.3f}% | {100 * p['same_patch_share']:.1f}% | "
          f"{ratio:.2f} | {order} |")
PY
