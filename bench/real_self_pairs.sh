#!/usr/bin/env bash
# Real meshes against their own re-tessellation ("a mesh against its own re-tessellation
# at most 0.2% mean"), with landmarks picked as a user might, not at finger tips: the vertices at
# the extremes of the mesh's principal axes. Each mesh is re-tessellated by `qs-family
# retessellate` (exact map kept), the pair dissected with qs-dissect as a user would and measured
# with `qs-metro --correspondence` (chart map). The ideal answer is the identity.
#
#   usage: bench/real_self_pairs.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-real-self-pairs)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 30000), DISSECT_ARGS (extra qs-dissect options),
#          PAIRS (default: the 18 pairs below, as "MESH:LAYOUT ..."),
#          RETESS_ARGS (extra qs-family retessellate options, e.g. "--keep-shape": a re-tessellation
#          that keeps thin parts, where the default isotropic one cuts them by up to 3% of the diagonal)
#
# Layouts: (a) seeds at both ends of principal axes 0 and 1, features at both ends of axis 2;
#          (b) seeds along axes 0 and 2, features along axis 1 (axes by decreasing variance).
# Prints per pair: dissect exit, time, mean / p95 / max error (% of the diagonal) and the
# similarity + nearest-point baseline's mean / max; then the mean over the pairs and how many
# are within 0.2% mean. "surfaces apart": how far the re-tessellation's chords are from the mesh
# (the ground truth between vertices is no closer than that).
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-real-self-pairs}
TOOLS=${QS_TOOLS:-build/tools}
SAMPLES=${SAMPLES:-30000}
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
read -r -a RETESS <<< "${RETESS_ARGS:-}"
PAIRS=${PAIRS:-"horse_5k.obj:a armadillo_29k.obj:a cat_sumner_14k.obj:a elephant_12k.obj:a armadillo_29k.obj:b
camel_4k_fixed.obj:b cow2_9k.off:b fish_blub_2k.obj:b goathead_6k.obj:b homer_12k.obj:b horse_5k.obj:b
igea_17k.off:b koala_7k.obj:b lion_sumner_10k.obj:b max_planck_11k.obj:b pig_4k.off:b polygirl_20k.off:b
spot_6k.obj:b"}
mkdir -p "$OUT"
RESULTS="$OUT/results.tsv"
: > "$RESULTS"

# Landmarks at the extremes of the principal axes (vertex ids).
axis_landmarks() {
  python3 - "$1" "$2" "$3" <<'EOF'
import json, sys
path, layout, out = sys.argv[1], sys.argv[2], sys.argv[3]
pts = []
with open(path) as f:
    if path.endswith(".off"):
        tok = f.read().split()
        i = 1 if tok[0].upper() == "OFF" else 0
        nv = int(tok[i])
        vals = tok[i + 3:i + 3 + 3 * nv]
        pts = [list(map(float, vals[3 * k:3 * k + 3])) for k in range(nv)]
    else:
        for line in f:
            p = line.split()
            if p and p[0] == "v":
                pts.append(list(map(float, p[1:4])))
sys.path.insert(0, "examples")
from pick_landmarks import principal_axes  # noqa: E402 (plain Python: no numpy in the base image)
c, axes = principal_axes(pts)
proj = [[sum((q[i] - c[i]) * d[i] for i in range(3)) for _, d in axes] for q in pts]
n = len(pts)
def arg(a, best):
    return max(range(n), key=lambda v: best * proj[v][a])
s1, s2, f = (0, 1, 2) if layout == "a" else (0, 2, 1)
seeds = [arg(s1, 1), arg(s2, 1), arg(s1, -1), arg(s2, -1)]
feats = {"axis_min": arg(f, -1), "axis_max": arg(f, 1)}
json.dump({"seeds": seeds, "features": feats}, open(out, "w"))
EOF
}

for pair in $PAIRS; do
  mesh=${pair%%:*}
  layout=${pair##*:}
  name="${mesh%.*}-$layout"
  dir="$OUT/$name"
  mkdir -p "$dir"
  axis_landmarks "$MESHES/$mesh" "$layout" "$dir/a.landmarks.json" || exit 1
  cp "$MESHES/$mesh" "$dir/a.${mesh##*.}"
  "$TOOLS/qs-family" retessellate "$dir/a.${mesh##*.}" --landmarks "$dir/a.landmarks.json" -o "$dir/b.obj" --quiet "${RETESS[@]}" ||
    exit 1
  t0=$(date +%s.%N)
  "$TOOLS/qs-dissect" "$dir/a.${mesh##*.}" "$dir/b.obj" --landmarks "$dir/a.landmarks.json" "$dir/b.landmarks.json" \
      -o "$dir/dissection" --quiet --report "$dir/report.txt" "${EXTRA[@]}" > "$dir/dissect.log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  secs=$(python3 -c "print(f'{$t1-$t0:.2f}')")
  if [ -f "$dir/dissection/dissection.json" ] &&
     "$TOOLS/qs-metro" --correspondence "$dir/dissection" --samples "$SAMPLES" --json -o "$dir/corr.json" \
       > "$dir/metro.log" 2>&1; then
    printf '%s\t%s\t%s\t%s\n' "$name" "$rc" "$secs" "$dir/corr.json" >> "$RESULTS"
  else
    printf '%s\t%s\t%s\t-\n' "$name" "$rc" "$secs" >> "$RESULTS"
  fi
done

python3 - "$RESULTS" <<'EOF'
import json, sys
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
print("| pair | exit | time | mean / p95 / max | baseline mean / max | surfaces apart (max) |")
print("|---|---:|---:|---:|---:|---:|")
means = []
for name, rc, secs, path in rows:
    if path == "-":
        print(f"| {name} | {rc} | {secs} s | - | - | - |")
        continue
    p = json.load(open(path))["pairs"][0]
    e, b = p["dissection"], p["baseline"]
    means.append(e["mean_percent"])
    print(f"| {name} | {rc} | {secs} s | {e['mean_percent']:.2f} / {e['p95_percent']:.2f} / {e['max_percent']:.1f}% | "
          f"{b['mean_percent']:.2f} / {b['max_percent']:.2f}% | {p['truth_tolerance_percent']:.2f}% |")
if means:
    within = sum(m <= 0.2 for m in means)
    print(f"mean over {len(means)} measured pairs: {sum(means) / len(means):.3f}%; within 0.2% mean: {within}; "
          f"dissected: {len(means)} of {len(rows)}")
EOF
