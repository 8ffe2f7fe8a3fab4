#!/usr/bin/env bash
# Correspondence benchmark: every pair is dissected with qs-dissect as a user would
# (landmarks given), then measured with `qs-metro --correspondence` against its exact ground truth.
#
#   usage: bench/correspondence.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-correspondence)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 100000), FACES (default 8000),
#          DISSECT_ARGS (extra qs-dissect options, e.g. "--no-refine-maps" or "--config FILE" with
#          {"geodesic_seed_curves": false, "intrinsic_cotan": false} for the old maps; the table then
#          shows the dissection's and the refinement's own times from qs-dissect's report)
#
# Pairs (data made here, nothing committed but the SMPL landmark file):
#   gen-sS        generated pair (qs-family, seed S = 1, 2, 3): two warps of one base, own tessellations
#   gen-v0        one smooth surface (qs-family --variation 0) with two tessellations (ideal: the identity)
#   fam4-s1       a family of 4 dissected together; shape00 against each of the other three
#   fam8-s1       a family of 8 dissected together; shape00 against the 7 others, averaged
#   self-gen      a generated shape against its own re-tessellation (ideal: the identity)
#   self-smpl-*   smpl_man_14k / smpl_woman_14k against its own re-tessellation (ideal: the identity)
#   human-retess  smpl_man_14k against smpl_woman_14k re-tessellated (same pose, registered)
#                 (re-tessellated by qs-family retessellate --keep-shape; the rows "(isotropic
#                 re-tessellation)" again with the default isotropic one, which cuts fingers and toes)
#   human-same    smpl_man_14k against smpl_woman_14k as shipped (identical connectivity)
#   ... --no-same-pose  the same-pose pairs again with qs-dissect --same-pose no (qs-dissect finds
#                 that they share a pose and treats them so by default; this row is without it)
# Seeds of the humans: middle fingers and big toes; features: nose, head top, heels
# (bench/correspondence/smpl.landmarks.json, SMPL vertex ids).
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-correspondence}
TOOLS=${QS_TOOLS:-build/tools}
SAMPLES=${SAMPLES:-100000}
FACES=${FACES:-8000}
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
LM=bench/correspondence/smpl.landmarks.json
mkdir -p "$OUT"
RESULTS="$OUT/results.tsv"
: > "$RESULTS"

# dissect NAME OUTDIR MESH... -- LANDMARKS...   ; then measure with the remaining args (maps)
run_pair() {
  local name=$1 dir=$2; shift 2
  local meshes=() lms=() maps=()
  while [ "$1" != "--" ]; do meshes+=("$1"); shift; done; shift
  while [ "$1" != "--" ]; do lms+=("$1"); shift; done; shift
  maps=("$@")
  local t0 t1 rc
  t0=$(date +%s.%N)
  "$TOOLS/qs-dissect" "${meshes[@]}" --landmarks "${lms[@]}" -o "$dir" --quiet --report "$dir.report.txt" \
      "${EXTRA[@]}" > "$dir.dissect.log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  local secs; secs=$(python3 -c "print(f'{$t1-$t0:.2f}')")
  if [ ! -f "$dir/dissection.json" ]; then
    printf '%s\t%s\t%s\t%s\n' "$name" "$rc" "$secs" "-" >> "$RESULTS"
    echo "$name: qs-dissect exit $rc, nothing to measure ($(tail -n1 "$dir.dissect.log"))"
    return
  fi
  local mapargs=()
  [ ${#maps[@]} -gt 0 ] && mapargs=(--map "${maps[@]}")
  if "$TOOLS/qs-metro" --correspondence "$dir" "${mapargs[@]}" --samples "$SAMPLES" --json -o "$dir.corr.json" \
      > "$dir.metro.log" 2>&1 &&
     "$TOOLS/qs-metro" --correspondence "$dir" "${mapargs[@]}" --samples "$SAMPLES" --level 4 --json \
      -o "$dir.corr-L4.json" >> "$dir.metro.log" 2>&1; then
    printf '%s\t%s\t%s\t%s\n' "$name" "$rc" "$secs" "$dir.corr.json" >> "$RESULTS"
    echo "$name: dissect exit $rc in $secs s, measured"
  else
    printf '%s\t%s\t%s\t%s\n' "$name" "$rc" "$secs" "-" >> "$RESULTS"
    echo "$name: measuring failed: $(tail -n1 "$dir.metro.log")"
  fi
}

# Generated pairs.
for s in 1 2 3; do
  g="$OUT/gen-s$s"
  "$TOOLS/qs-family" generate -n 2 --seed "$s" --faces "$FACES" --quiet -o "$g" || exit 1
  run_pair "gen-s$s" "$g/dissection" "$g/shape00.obj" "$g/shape01.obj" -- \
      "$g/shape00.landmarks.json" "$g/shape01.landmarks.json" --
done

# One smooth surface tessellated twice (--variation 0): tessellation independence with an exact map.
v="$OUT/gen-v0"
"$TOOLS/qs-family" generate -n 2 --seed 1 --variation 0 --faces "$FACES" --quiet -o "$v" || exit 1
run_pair "gen-v0" "$v/dissection" "$v/shape00.obj" "$v/shape01.obj" -- \
    "$v/shape00.landmarks.json" "$v/shape01.landmarks.json" --

# A family of 4 dissected together.
f="$OUT/fam4-s1"
"$TOOLS/qs-family" generate -n 4 --seed 1 --faces "$FACES" --quiet -o "$f" || exit 1
run_pair "fam4-s1" "$f/dissection" "$f"/shape0{0,1,2,3}.obj -- "$f"/shape0{0,1,2,3}.landmarks.json --

# A family of 8 (summarized in one row: the average over the 7 pairs, the largest max).
f="$OUT/fam8-s1"
"$TOOLS/qs-family" generate -n 8 --seed 1 --faces "$FACES" --quiet -o "$f" || exit 1
run_pair "fam8-s1" "$f/dissection" "$f"/shape0{0,1,2,3,4,5,6,7}.obj -- "$f"/shape0{0,1,2,3,4,5,6,7}.landmarks.json --

# A generated shape against its own re-tessellation.
g="$OUT/gen-s1"
"$TOOLS/qs-family" retessellate "$g/shape00.obj" --landmarks "$g/shape00.landmarks.json" \
    -o "$OUT/self-gen/shape00_r.obj" --quiet || exit 1
run_pair "self-gen" "$OUT/self-gen/dissection" "$g/shape00.obj" "$OUT/self-gen/shape00_r.obj" -- \
    "$g/shape00.landmarks.json" "$OUT/self-gen/shape00_r.landmarks.json" -- - "$OUT/self-gen/shape00_r.map.json"
BASE_EXTRA=("${EXTRA[@]}")
EXTRA=("${BASE_EXTRA[@]}" --same-pose no)
run_pair "self-gen --no-same-pose" "$OUT/self-gen/dissection-unposed" "$g/shape00.obj" "$OUT/self-gen/shape00_r.obj" -- \
    "$g/shape00.landmarks.json" "$OUT/self-gen/shape00_r.landmarks.json" -- - "$OUT/self-gen/shape00_r.map.json"
EXTRA=("${BASE_EXTRA[@]}")

if [ -f "$MESHES/smpl_man_14k.obj" ] && [ -f "$MESHES/smpl_woman_14k.obj" ]; then
  h="$OUT/human"
  mkdir -p "$h"
  # The bodies re-tessellated keeping their shape (fingers and toes kept; the surfaces at most
  # 0.18% of the diagonal apart), and isotropically at the body's face count (which cuts the
  # fingers and toes: 0.65% apart, the hands losing 14-27% of their area), in iso/.
  mkdir -p "$h/iso"
  for body in smpl_man_14k smpl_woman_14k; do
    "$TOOLS/qs-family" retessellate "$MESHES/$body.obj" --landmarks "$LM" --keep-shape -o "$h/${body}_r.obj" --quiet ||
      exit 1
    "$TOOLS/qs-family" retessellate "$MESHES/$body.obj" --landmarks "$LM" -o "$h/iso/${body}_r.obj" --quiet || exit 1
  done
  # human_pairs LABEL_SUFFIX DIR_SUFFIX [RETESS_DIR]: the body pairs with the current EXTRA options
  # (the three with a re-tessellation only when RETESS_DIR is given; human-same otherwise).
  human_pairs() {
    local r=${3:-$h}
    run_pair "self-smpl-man$1" "$h/self-man$2" "$MESHES/smpl_man_14k.obj" "$r/smpl_man_14k_r.obj" -- \
        "$LM" "$r/smpl_man_14k_r.landmarks.json" -- - "$r/smpl_man_14k_r.map.json"
    run_pair "self-smpl-woman$1" "$h/self-woman$2" "$MESHES/smpl_woman_14k.obj" "$r/smpl_woman_14k_r.obj" -- \
        "$LM" "$r/smpl_woman_14k_r.landmarks.json" -- - "$r/smpl_woman_14k_r.map.json"
    run_pair "human-retess$1" "$h/retess$2" "$MESHES/smpl_man_14k.obj" "$r/smpl_woman_14k_r.obj" -- \
        "$LM" "$r/smpl_woman_14k_r.landmarks.json" -- - "$r/smpl_woman_14k_r.map.json"
    [ -n "${3:-}" ] && return
    run_pair "human-same$1" "$h/same$2" "$MESHES/smpl_man_14k.obj" "$MESHES/smpl_woman_14k.obj" -- "$LM" "$LM" -- - -
  }
  human_pairs "" ""
  human_pairs " (isotropic re-tessellation)" "-iso" "$h/iso"
  # The same-pose pairs again with qs-dissect --same-pose no (found to share a pose by default).
  BASE_EXTRA=("${EXTRA[@]}")
  EXTRA=("${BASE_EXTRA[@]}" --same-pose no)
  human_pairs " --no-same-pose" "-unposed"
  EXTRA=("${BASE_EXTRA[@]}")
else
  echo "no smpl_man_14k / smpl_woman_14k in $MESHES: human pairs skipped"
fi

# The table (Markdown): one row per measured pair (A = the first mesh of the dissection).
python3 - "$RESULTS" <<'PY'
import json, re, sys
def timing(path, secs):
    # "0.42 s" or, with the map refinement, "0.42 s (dissect 0.30 + refine 0.08)" from qs-dissect's report
    try:
        rep = open(path.replace(".corr.json", ".report.txt")).read()
    except OSError:
        return f"{secs} s"
    m = re.search(r"dissect ([0-9.]+) s, refine maps ([0-9.]+) s", rep)
    return f"{secs} s (dissect {float(m.group(1)):.2f} + refine {float(m.group(2)):.2f})" if m else f"{secs} s"
print()
print("| pair | dissect exit | time | patches | mean | median | p95 | max | same patch | level 4: mean / p95 / max | baseline mean | baseline p95 | baseline max | truth within (mean / max) | corners (mean / max) | distortion median: qs / truth |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for line in open(sys.argv[1]):
    name, rc, secs, path = line.rstrip("\n").split("\t")
    if path == "-":
        print(f"| {name} | {rc} | {secs} s | | not measured | | | | | | | | | | |")
        continue
    doc = json.load(open(path))
    l4 = json.load(open(path.replace(".corr.json", ".corr-L4.json")))["pairs"]
    rows = list(zip(doc["pairs"], l4))
    if len(rows) > 3:  # a large family: one row, averages over the pairs and the largest max
        def avg(pairs, key, stat, red=lambda v: sum(v) / len(v)):
            return red([p[key][stat] for p in pairs])
        P, Q = doc["pairs"], l4
        m = {k: avg(P, "dissection", k + "_percent") for k in ("mean", "median", "p95")}
        m["max"] = avg(P, "dissection", "max_percent", max)
        b = {k: avg(P, "baseline", k + "_percent") for k in ("mean", "p95")}
        b["max"] = avg(P, "baseline", "max_percent", max)
        share = sum(p["same_patch_share"] for p in P) / len(P)
        print(f"| {name} (average of {len(P)} pairs, largest max) | {rc} | {timing(path, secs)} | {doc['patches']} | {m['mean']:.2f}% | "
              f"{m['median']:.2f}% | {m['p95']:.2f}% | {m['max']:.2f}% | {100*share:.1f}% | "
              f"{avg(Q, 'dissection', 'mean_percent'):.2f} / {avg(Q, 'dissection', 'p95_percent'):.2f} / "
              f"{avg(Q, 'dissection', 'max_percent', max):.2f}% | {b['mean']:.2f}% | {b['p95']:.2f}% | {b['max']:.2f}% | exact | "
              f"{sum(p.get('corner_distance_mean_percent', 0) for p in P) / len(P):.2f} / "
              f"{max(p.get('corner_distance_max_percent', 0) for p in P):.2f}% | "
              f"{avg(P, 'distortion', 'dissection_median'):.3f} / {avg(P, 'distortion', 'truth_median'):.3f} |")
        continue
    for p, q in rows:
        a = p["a"].rsplit("/", 1)[-1]; b = p["b"].rsplit("/", 1)[-1]
        d, bl = p["dissection"], p["baseline"]
        label = name if len(doc["pairs"]) == 1 else f"{name} {a}->{b}"
        t, tm = p["truth_tolerance_percent"], p["truth_tolerance_mean_percent"]
        tol = "exact" if t == 0 else f"{tm:.3f}% / {t:.2f}%"
        print(f"| {label} | {rc} | {timing(path, secs)} | {doc['patches']} | {d['mean_percent']:.2f}% | {d['median_percent']:.2f}% | "
              f"{d['p95_percent']:.2f}% | {d['max_percent']:.2f}% | {100*p['same_patch_share']:.1f}% | "
              f"{q['dissection']['mean_percent']:.2f} / {q['dissection']['p95_percent']:.2f} / {q['dissection']['max_percent']:.2f}% | "
              f"{bl['mean_percent']:.2f}% | {bl['p95_percent']:.2f}% | {bl['max_percent']:.2f}% | {tol} | "
              f"{p.get('corner_distance_mean_percent', 0):.2f} / {p.get('corner_distance_max_percent', 0):.2f}% | "
              f"{p['distortion']['dissection_median']:.3f} / {p['distortion']['truth_median']:.3f} |")
PY
