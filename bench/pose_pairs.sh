#!/usr/bin/env bash
# Pose pairs with exact ground truth (docs/pose-pairs.md): each shared mesh against itself in
# another pose (`qs-family pose`: limbs bent or turned as rigidly as possible, vertices and faces
# kept, so vertex i <-> vertex i is the exact map), and against that pose re-tessellated
# (`--retessellate --keep-shape`: a "surface" map onto the posed mesh). Every pair is dissected
# with qs-dissect as a user would (the landmarks given) and measured with `qs-metro
# --correspondence` (chart map, level-4 common remesh and what an exact map loses through that
# remesh) beside the similarity + nearest-point baseline and the registration alone
# (`qs-bench-registration`: B's points through the registration's inverse, as qs-dissect takes
# them); then the seed loop's agreement: the share of the area whose
# exact image lies on the same side of the other mesh's seed loop (level-0 patch), and the same
# patch (leaf) share.
# Last, another person in another pose: smpl_man_14k against the posed smpl_woman_14k (and its
# re-tessellation), when both are in the list.
#
#   usage: bench/pose_pairs.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-pose-pairs)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 30000), SEED (pose seed, default 1),
#          POSE_ARGS (extra qs-family pose options), DISSECT_ARGS (extra qs-dissect options),
#          MESHES_LIST (default: the meshes below, smallest first), FEATURES (give qs-dissect the
#          seeds and only the first N features by name, as a user whose landmarks leave limbs free;
#          default all)
# Landmarks: the SMPL bodies use bench/correspondence/smpl.landmarks.json (finger tips, big toes;
# nose, head top, heels); the other meshes get 4 seeds and 2-6 features at their extremities
# (qs-family pose chooses them, seeds in the order of their shortest loop).
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-pose-pairs}
TOOLS=${QS_TOOLS:-build/tools}
BENCH=${QS_BENCH:-build/bench}
SAMPLES=${SAMPLES:-30000}
SEED=${SEED:-1}
read -r -a POSE <<< "${POSE_ARGS:-}"
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
FEATURES=${FEATURES:-}
LIST=${MESHES_LIST:-"pig_4k.off camel_4k_fixed.obj horse_5k.obj cow2_9k.off lion_sumner_10k.obj elephant_12k.obj
cat_sumner_14k.obj smpl_man_14k.obj smpl_woman_14k.obj polygirl_20k.off armadillo_29k.obj"}
mkdir -p "$OUT"
RESULTS="$OUT/results.tsv"
ATTRIBUTION="$OUT/attribution.tsv"
: > "$RESULTS"
: > "$ATTRIBUTION"

# STAGES: what each stage costs (qs-bench-stage-attribution): the posed pair again with B's stages
# replaced, one more at a time, by their exact counterparts taken from A: the bench's options per
# level (the table's columns below name them).
STAGES=("--exact loop" "--exact splits" "--exact maps" "--exact maps --no-refine"
        "--exact maps --no-refine --leaf-rounds 0")
# attribution NAME DIR A B LA LB: one line per pair: NAME, then per level "exit:folder" ("exit:-"
# when nothing was measured).
attribution() {
  local name=$1 dir=$2 line=$1 k=0 rc level args
  [ -x "$BENCH/qs-bench-stage-attribution" ] || return 0
  local la lb
  la=$(given "$5" "$(dirname "$dir")")
  lb=$(given "$6" "$(dirname "$dir")")
  for level in "${STAGES[@]}"; do
    read -r -a args <<< "$level"
    "$BENCH/qs-bench-stage-attribution" "$3" "$4" --landmarks "$la" "$lb" "${args[@]}" -o "$dir-$k" > "$dir-$k.log" 2>&1
    rc=$?
    if [ -f "$dir-$k/dissection.json" ] &&
       "$TOOLS/qs-metro" --correspondence "$dir-$k" --samples "$SAMPLES" --json -o "$dir-$k.corr.json" \
         > "$dir-$k.metro.log" 2>&1; then
      line+=$'\t'"$rc:$dir-$k"
    else
      line+=$'\t'"$rc:-"
    fi
    k=$((k + 1))
  done
  printf '%s\n' "$line" >> "$ATTRIBUTION"
}

# given LANDMARKS DIR: the landmark file qs-dissect gets (with FEATURES, a copy in DIR with the
# seeds and the first FEATURES features by name only, so that every mesh keeps the same ones).
given() {
  if [ -z "$FEATURES" ]; then echo "$1"; return; fi
  local out
  out="$2/few-$(basename "$1")"
  python3 - "$1" "$out" "$FEATURES" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
f = {k: d['features'][k] for k in sorted(d.get('features', {}))[:int(sys.argv[3])]}
json.dump({'seeds': d['seeds'], 'features': f}, open(sys.argv[2], 'w'))
PY
  echo "$out"
}

# pair NAME DIR A B LANDMARKS_A LANDMARKS_B MAP_B POSED_OBJ
pair() {
  local name=$1 dir=$2 a=$3 b=$4 la=$5 lb=$6 mb=$7 posed=$8
  local t0 t1 rc secs
  la=$(given "$la" "$(dirname "$dir")")
  lb=$(given "$lb" "$(dirname "$dir")")
  t0=$(date +%s.%N)
  "$TOOLS/qs-dissect" "$a" "$b" --landmarks "$la" "$lb" -o "$dir" --quiet --report "$dir.report.txt" "${EXTRA[@]}" \
      > "$dir.dissect.log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  secs=$(python3 -c "print(f'{$t1-$t0:.2f}')")
  if [ -f "$dir/dissection.json" ] &&
     "$TOOLS/qs-metro" --correspondence "$dir" --map - "$mb" --samples "$SAMPLES" --json -o "$dir.corr.json" \
       > "$dir.metro.log" 2>&1 &&
     "$TOOLS/qs-metro" --correspondence "$dir" --map - "$mb" --samples "$SAMPLES" --level 4 --json \
       -o "$dir.corr-L4.json" >> "$dir.metro.log" 2>&1; then
    # The registration alone, as qs-dissect uses it (its inverse, B -> A), when the bench is built.
    if [ -x "$BENCH/qs-bench-registration" ]; then
      local map=()
      [ "$mb" != - ] && map=("$mb")
      "$BENCH/qs-bench-registration" "$a" "$b" "$la" "$lb" "$posed" "${map[@]}" > "$dir.registration.txt" 2>&1
    fi
    printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$name" "$rc" "$secs" "$dir" "$mb" "$posed" >> "$RESULTS"
    echo "$name: dissect exit $rc in $secs s, measured"
  else
    printf '%s\t%s\t%s\t-\t-\t-\n' "$name" "$rc" "$secs" >> "$RESULTS"
    echo "$name: dissect exit $rc in $secs s, not measured ($(tail -n1 "$dir.dissect.log"))"
  fi
}

for mesh in $LIST; do
  [ -f "$MESHES/$mesh" ] || { echo "$mesh: not in $MESHES, skipped"; continue; }
  stem=${mesh%.*}
  d="$OUT/$stem"
  mkdir -p "$d"
  lmargs=()
  case $stem in smpl_*) lmargs=(--landmarks bench/correspondence/smpl.landmarks.json) ;; esac
  t0=$(date +%s.%N)
  if ! "$TOOLS/qs-family" pose "$MESHES/$mesh" "${lmargs[@]}" --seed "$SEED" "${POSE[@]}" --retessellate --keep-shape \
       -o "$d/posed.obj" > "$d/pose.log" 2>&1; then
    echo "$stem: qs-family pose failed: $(tail -n1 "$d/pose.log")"
    printf '%s\t%s\t-\t-\t-\t-\n' "$stem" "pose failed" >> "$RESULTS"
    continue
  fi
  t1=$(date +%s.%N)
  echo "$stem: posed in $(python3 -c "print(f'{$t1-$t0:.1f}')") s: $(head -n1 "$d/pose.log" | sed 's/.*faces; //')"
  pair "$stem" "$d/dissection" "$MESHES/$mesh" "$d/posed.obj" "$d/posed.source.landmarks.json" \
      "$d/posed.landmarks.json" - "$d/posed.obj"
  attribution "$stem" "$d/exact" "$MESHES/$mesh" "$d/posed.obj" "$d/posed.source.landmarks.json" \
      "$d/posed.landmarks.json"
  pair "$stem re-tessellated" "$d/dissection-r" "$MESHES/$mesh" "$d/posed_r.obj" "$d/posed.source.landmarks.json" \
      "$d/posed_r.landmarks.json" "$d/posed_r.map.json" "$d/posed.obj"
done

# Another person in another pose: smpl_man_14k against smpl_woman_14k's pose. The SMPL bodies
# share their connectivity, so vertex i <-> vertex i is the exact map here too.
w="$OUT/smpl_woman_14k"
if [ -f "$MESHES/smpl_man_14k.obj" ] && [ -f "$w/posed.obj" ]; then
  mkdir -p "$OUT/man-woman"
  pair "smpl_man_14k -> smpl_woman_14k posed" "$OUT/man-woman/dissection" "$MESHES/smpl_man_14k.obj" "$w/posed.obj" \
      bench/correspondence/smpl.landmarks.json "$w/posed.landmarks.json" - "$w/posed.obj"
  pair "smpl_man_14k -> smpl_woman_14k posed, re-tessellated" "$OUT/man-woman/dissection-r" \
      "$MESHES/smpl_man_14k.obj" "$w/posed_r.obj" bench/correspondence/smpl.landmarks.json "$w/posed_r.landmarks.json" \
      "$w/posed_r.map.json" "$w/posed.obj"
fi

QS_BENCH_DIR="$(dirname "$0")" python3 - "$RESULTS" "$ATTRIBUTION" <<'PY'
import json, math, os, sys

sys.path.insert(0, os.environ['QS_BENCH_DIR'])
from qs_chart import read_chart

def obj_faces(path):
    return [[int(t.split('/')[0]) - 1 for t in l.split()[1:4]] for l in open(path) if l.startswith('f ')]

def sides(dissection, i, nv):
    """Per input vertex of mesh i: bit 1 / 2 when a chart face of seed patch 0 / 1 touches it, and
    the vertex's area (a third of its chart faces')."""
    doc = json.load(open(os.path.join(dissection, 'dissection.json')))
    m = doc['meshes'][i]
    P, F = read_chart(os.path.join(dissection, m['chart']))
    top = [1 << int(p['name'].split('.')[0]) for p in m['patches']]
    side, w = [0] * len(P), [0.0] * len(P)
    for (a, b, c), patch in F:
        u = [P[b][k] - P[a][k] for k in range(3)]
        v = [P[c][k] - P[a][k] for k in range(3)]
        x = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        area = 0.5 * math.sqrt(sum(t * t for t in x))
        for q in (a, b, c):
            side[q] |= top[patch]
            w[q] += area / 3
    return side[:nv], w[:nv]

def same_side(dissection, mb, posed):
    """The share of B's area (per vertex) whose exact image on A lies on the same side of A's seed
    loop as it lies of B's (a vertex on a loop agrees with either side)."""
    faces = obj_faces(posed)
    nv_a = max(max(f) for f in faces) + 1
    sa, _ = sides(dissection, 0, nv_a)
    if mb == '-':
        sb, wb = sides(dissection, 1, nv_a)
        image = sa
    else:
        origins = json.load(open(mb))['origins']
        sb, wb = sides(dissection, 1, len(origins))
        image = [sa[faces[int(o[0])][max(range(3), key=lambda k: o[1 + k])]] for o in origins]
    agree = sum(w for w, x, y in zip(wb, image, sb) if x & y)
    return agree / sum(wb)

def registration(d):
    """The registration's inverse alone (qs-bench-registration), as 'mean / p95 / max%', or ''."""
    try:
        for l in open(d + '.registration.txt'):
            if l.startswith('registered, inverse'):
                return l.split(': ', 1)[1].strip()
    except OSError:
        pass
    return ''

rows = [l.rstrip('\n').split('\t') for l in open(sys.argv[1])]
f = lambda s: f"{s['mean_percent']:.2f} / {s['p95_percent']:.2f} / {s['max_percent']:.2f}%"
print()
print('| pair | exit | time | patches | qs: mean / p95 / max | registration alone | level 4: mean / p95 / max | level 4, an exact map: mean / p95 / max | baseline: mean / p95 / max | same side of the seed loop | same patch | corners (mean) |')
print('|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
for name, rc, secs, d, mb, posed in rows:
    if d == '-':
        print(f'| {name} | {rc} | {secs} s | | not measured | | | | | | | |')
        continue
    doc = json.load(open(d + '.corr.json'))
    p = doc['pairs'][0]
    q = json.load(open(d + '.corr-L4.json'))['pairs'][0]
    e, b, e4, r4 = p['dissection'], p['baseline'], q['dissection'], q['remesh_alone']
    side = same_side(d, mb, posed)
    print(f"| {name} | {rc} | {secs} s | {doc['patches']} | {f(e)} | {registration(d)} | {f(e4)} | {f(r4)} | {f(b)} | {100 * side:.1f}% | "
          f"{100 * p['same_patch_share']:.1f}% | {p.get('corner_distance_mean_percent', 0):.2f}% |")

# What each stage costs: B's stages replaced one more at a time by A's (the levels of STAGES).
qs_rows = {r[0]: r for r in rows}
levels = ['exact seed loop', '+ exact splits', '+ exact node maps', '+ no refinement', '+ no leaf rounds']
exact = [l.rstrip('\n').split('\t') for l in open(sys.argv[2])]
if exact:
    print()
    print('| pair | qs | ' + ' | '.join(levels) + ' |')
    print('|---|' + '---:|' * (len(levels) + 1))
    for cols in exact:
        name = cols[0]
        r = qs_rows.get(name)
        cells = [f(json.load(open(r[3] + '.corr.json'))['pairs'][0]['dissection']) if r and r[3] != '-' else 'not measured']
        for c in cols[1:]:
            rc, d = c.split(':', 1)
            v = f(json.load(open(d + '.corr.json'))['pairs'][0]['dissection']) if d != '-' else 'not measured'
            cells.append(v if rc == '0' else f'exit {rc}: {v}')
        print(f"| {name} | " + ' | '.join(cells) + ' |')
PY
