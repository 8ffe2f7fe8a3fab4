#!/usr/bin/env bash
# Pose pairs with exact ground truth (docs/pose-pairs.md): each shared mesh against itself in
# another pose (`qs-family pose`: limbs bent or turned as rigidly as possible, vertices and faces
# kept, so vertex i <-> vertex i is the exact map), and against that pose re-tessellated
# (`--retessellate --keep-shape`: a "surface" map onto the posed mesh). Every pair is dissected
# with qs-dissect as a user would (the landmarks given) and measured with `qs-metro
# --correspondence` (chart map and level-4 common remesh) beside the similarity + nearest-point
# baseline; then the seed loop's agreement: the share of the area whose exact image lies on the same
# side of the other mesh's seed loop (level-0 patch), and the same patch (leaf) share.
#
#   usage: bench/pose_pairs.sh [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-pose-pairs)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 30000), SEED (pose seed, default 1),
#          POSE_ARGS (extra qs-family pose options), DISSECT_ARGS (extra qs-dissect options),
#          MESHES_LIST (default: the meshes below, smallest first)
# Landmarks: the SMPL bodies use bench/correspondence/smpl.landmarks.json (finger tips, big toes;
# nose, head top, heels); the other meshes get 4 seeds and 2-6 features at their extremities
# (qs-family pose chooses them, seeds in the order of their shortest loop).
set -uo pipefail
cd "$(dirname "$0")/.."
MESHES=${1:-../shared/meshes}
OUT=${2:-out/bench-pose-pairs}
TOOLS=${QS_TOOLS:-build/tools}
SAMPLES=${SAMPLES:-30000}
SEED=${SEED:-1}
read -r -a POSE <<< "${POSE_ARGS:-}"
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
LIST=${MESHES_LIST:-"pig_4k.off camel_4k_fixed.obj horse_5k.obj cow2_9k.off lion_sumner_10k.obj elephant_12k.obj
cat_sumner_14k.obj smpl_man_14k.obj smpl_woman_14k.obj polygirl_20k.off armadillo_29k.obj"}
mkdir -p "$OUT"
RESULTS="$OUT/results.tsv"
: > "$RESULTS"

# pair NAME DIR A B LANDMARKS_A LANDMARKS_B MAP_B POSED_OBJ
pair() {
  local name=$1 dir=$2 a=$3 b=$4 la=$5 lb=$6 mb=$7 posed=$8
  local t0 t1 rc secs
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
  pair "$stem re-tessellated" "$d/dissection-r" "$MESHES/$mesh" "$d/posed_r.obj" "$d/posed.source.landmarks.json" \
      "$d/posed_r.landmarks.json" "$d/posed_r.map.json" "$d/posed.obj"
done

/usr/bin/python3 - "$RESULTS" <<'PY'
import json, os, sys
import numpy as np

def read_chart(path):
    data = open(path, 'rb').read()
    h = data.index(b'end_header\n') + len(b'end_header\n')
    hdr = data[:h].decode('ascii', 'replace')
    nv = int(hdr.split('element vertex ')[1].split()[0])
    nf = int(hdr.split('element face ')[1].split()[0])
    tex = '<f8' if 'list uchar double texcoord' in hdr else '<f4'
    P = np.frombuffer(data, dtype='<f8', count=3 * nv, offset=h).reshape(-1, 3)
    rec = np.dtype([('n', 'u1'), ('v', '<i4', 3), ('m', 'u1'), ('t', tex, 6), ('p', '<i4'), ('c', 'u1', 3)])
    F = np.frombuffer(data, dtype=rec, count=nf, offset=h + 24 * nv)
    return P, F

def obj_faces(path):
    return np.array([[int(t.split('/')[0]) - 1 for t in l.split()[1:4]] for l in open(path) if l.startswith('f ')])

def sides(dissection, i, nv):
    """Per input vertex of mesh i: bit 1 / 2 when a chart face on seed patch 0 / 1 touches it;
    and the vertex's area (a third of its chart faces')."""
    doc = json.load(open(os.path.join(dissection, 'dissection.json')))
    m = doc['meshes'][i]
    P, F = read_chart(os.path.join(dissection, m['chart']))
    names = [p['name'] for p in m['patches']]
    top = np.array([1 << int(n.split('.')[0]) for n in names])
    V = F['v']
    area = 0.5 * np.linalg.norm(np.cross(P[V[:, 1]] - P[V[:, 0]], P[V[:, 2]] - P[V[:, 0]]), axis=1)
    side = np.zeros(len(P), dtype=int)
    w = np.zeros(len(P))
    for k in range(3):
        np.bitwise_or.at(side, V[:, k], top[F['p']])
        np.add.at(w, V[:, k], area / 3)
    return side[:nv], w[:nv]

def same_side(dissection, mb, posed):
    """The share of B's area (per vertex) whose exact image on A lies on the same side of A's seed loop
    as on B's (a vertex on a loop agrees with either side)."""
    faces = obj_faces(posed)
    nv_a = int(faces.max()) + 1
    sa, _ = sides(dissection, 0, nv_a)
    doc = json.load(open(os.path.join(dissection, 'dissection.json')))
    if mb == '-':
        sb, wb = sides(dissection, 1, nv_a)
        image = sa
    else:
        origins = json.load(open(mb))['origins']
        sb, wb = sides(dissection, 1, len(origins))
        image = np.array([sa[faces[int(o[0])][int(np.argmax(o[1:4]))]] for o in origins])
    agree = (image & sb) != 0
    return float((wb * agree).sum() / wb.sum())

rows = [l.rstrip('\n').split('\t') for l in open(sys.argv[1])]
print()
print('| pair | exit | time | patches | qs: mean / p95 / max | level 4: mean / p95 / max | baseline: mean / p95 / max | same side of the seed loop | same patch | corners (mean) |')
print('|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|')
for name, rc, secs, d, mb, posed in rows:
    if d == '-':
        print(f'| {name} | {rc} | {secs} s | | not measured | | | | | |')
        continue
    doc = json.load(open(d + '.corr.json'))
    p = doc['pairs'][0]
    q = json.load(open(d + '.corr-L4.json'))['pairs'][0]
    e, b, e4 = p['dissection'], p['baseline'], q['dissection']
    f = lambda s: f"{s['mean_percent']:.2f} / {s['p95_percent']:.2f} / {s['max_percent']:.2f}%"
    side = same_side(d, mb, posed)
    print(f"| {name} | {rc} | {secs} s | {doc['patches']} | {f(e)} | {f(e4)} | {f(b)} | {100 * side:.1f}% | "
          f"{100 * p['same_patch_share']:.1f}% | {p.get('corner_distance_mean_percent', 0):.2f}% |")
PY
