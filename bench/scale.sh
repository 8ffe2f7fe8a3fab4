#!/usr/bin/env bash
# How qs-dissect grows with its input, run as a user runs it: one mesh subdivided 1->4 per step
# (spot_6k, 6k to 6M faces), double cones whose caps are fans (one vertex of valence 5k-40k),
# generated families of 2-32 meshes dissected together (qs-family generate), a mesh paired
# with its own re-tessellation (qs-family retessellate, 40k-150k faces), a face re-tessellated
# twice (max_planck_11k to 28k and 140k faces), a set of four generated 100k-face meshes, and
# koala_100k and four smaller shared meshes against themselves in another pose re-tessellated to
# 140k faces.
# Every mesh is made by script (bench/scale_meshes.py, qs-family) into OUT_DIR/meshes and kept
# for the next run.
#
#   usage: bench/scale.sh [--quick] [MESH_DIR] [OUT_DIR]   (defaults: ../shared/meshes, out/bench-scale)
#   env:   QS_TOOLS (default build/tools)
#
# --quick: spot to 375k faces, the four cones, families of 1-16, one 40k pair and the face pair
# (about 70 s of CPU, 2-3 minutes on 2 busy cores, 300 MB). Without it: spot to 6M faces,
# families to 32, pairs to 150k, the four 100k-face meshes, the posed pairs (the 6M-face mesh alone takes minutes
# of CPU and about 4 GB of memory).
#
# Per run (qs-dissect as a user runs it: dissection and map refinement, all threads): wall time,
# CPU time (user + sys: what the run costs, less dependent on the machine's load),
# peak resident memory (/usr/bin/time), patches. "exponent": log(cpu ratio) / log(size ratio)
# against the row above (1 = linear); each table ends with the least-squares exponent of CPU
# time and of memory over its rows. Families: CPU time per mesh, and per mesh per patch (the
# union tree grows with N).
set -uo pipefail
cd "$(dirname "$0")/.."
quick=0
args=()
for a in "$@"; do
  case "$a" in
    --quick) quick=1 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) echo "scale.sh: unknown option $a (try --help)" >&2; exit 1 ;;
    *) args+=("$a") ;;
  esac
done
MESHES=${args[0]:-../shared/meshes}
OUT=${args[1]:-out/bench-scale}
TOOLS=${QS_TOOLS:-build/tools}
for t in qs-dissect qs-family; do
  [ -x "$TOOLS/$t" ] || { echo "scale.sh: $TOOLS/$t not found (build it first)" >&2; exit 3; }
done
[ -x /usr/bin/time ] || { echo "scale.sh: /usr/bin/time (GNU time) is needed for peak memory" >&2; exit 3; }
[ -f "$MESHES/spot_6k.obj" ] || { echo "scale.sh: $MESHES/spot_6k.obj not found" >&2; exit 3; }
M=$OUT/meshes
mkdir -p "$M" "$OUT/runs"
gen() { python3 bench/scale_meshes.py "$@" >/dev/null || { echo "scale.sh: scale_meshes.py $* failed" >&2; exit 1; }; }

# run NAME MESH... : dissects, prints "wall cpu peak_mb patches" (patches of the first mesh).
run() {
  local name=$1; shift
  local log=$OUT/runs/$name.txt tm=$OUT/runs/$name.time
  if ! /usr/bin/time -f "%e %U %S %M" -o "$tm" "$TOOLS/qs-dissect" "$@" -o "$OUT/runs/$name.dissection" \
      > "$log" 2>&1; then
    echo "scale.sh: qs-dissect failed on $name (see $log)" >&2
    echo "failed - - -"
    return
  fi
  local patches
  patches=$(grep -m1 -o '[0-9]* patches' "$log" | cut -d' ' -f1)
  awk -v p="${patches:--}" 'END { printf "%.2f %.2f %.0f %s\n", $1, $2 + $3, $4 / 1024, p }' "$tm"
  rm -rf "$OUT/runs/$name.dissection"
}

faces_of() {  # faces of an OFF or OBJ file
  case "$1" in
    *.off) awk 'NF && $1 !~ /^#/ && $1 != "OFF" { print $2; exit }' "$1" ;;
    *) grep -c '^f ' "$1" ;;
  esac
}

# table TITLE SIZE_HEADER rows...: each row "label size wall cpu mb patches"; prints a markdown
# table with the exponent per row and the fitted exponents.
table() {
  local title=$1 size_header=$2; shift 2
  echo
  echo "$title:"
  printf '%s\n' "$@" | awk -v sh="$size_header" '
    BEGIN { n = 0; printf "%-16s %10s %9s %8s %8s %8s %9s\n", "case", sh, "wall s", "CPU s", "peak MB", "patches", "exponent" }
    $3 == "failed" { printf "%-16s %10s %9s\n", $1, $2, "failed"; next }
    {
      e = "";
      if (n > 0 && $2 > ps && $4 > 0 && pc > 0) e = sprintf("%.2f", log($4 / pc) / log($2 / ps));
      printf "%-16s %10s %9s %8s %8s %8s %9s\n", $1, $2, $3, $4, $5, $6, e;
      if ($4 > 0) { x[n] = log($2); y[n] = log($4); z[n] = log($5); n++ }
      ps = $2; pc = $4
    }
    END {
      if (n >= 2) {
        for (i = 0; i < n; i++) { sx += x[i]; sy += y[i]; sz += z[i] }
        mx = sx / n; my = sy / n; mz = sz / n;
        for (i = 0; i < n; i++) { sxx += (x[i] - mx)^2; sxy += (x[i] - mx) * (y[i] - my); sxz += (x[i] - mx) * (z[i] - mz) }
        printf "\nfitted growth: CPU time ~ n^%.2f, peak memory ~ n^%.2f (%d sizes)\n", sxy / sxx, sxz / sxx, n
      }
    }'
}

echo "qs-dissect at scale ($( [ "$quick" = 1 ] && echo quick || echo full ) set); $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"

# 1. One mesh, subdivided.
steps=5
[ "$quick" = 1 ] && steps=3
rows=()
for s in $(seq 0 "$steps"); do
  f=$M/spot_s$s.off
  [ -f "$f" ] || gen subdivide "$s" "$MESHES/spot_6k.obj" "$f"
  n=$(faces_of "$f")
  echo "== spot subdivided $s times: $n faces" >&2
  rows+=("spot_s$s $n $(run "spot_s$s" "$f")")
done
table "One mesh subdivided (spot_6k, 1->4 midpoint subdivision per step)" faces "${rows[@]}"

# 2. Fan caps.
rows=()
for k in 5000 10000 20000 40000; do
  f=$M/cone_$k.off
  [ -f "$f" ] || gen cone "$k" "$f"
  echo "== cone of valence $k" >&2
  rows+=("cone_$k $k $(run "cone_$k" "$f")")
done
table "Double cones with fan caps (one vertex of valence k, 2k faces)" valence "${rows[@]}"

# 3. Generated families dissected together (8000 faces a mesh; shape i does not depend on N).
maxn=32
[ "$quick" = 1 ] && maxn=16
fam=$M/family8k
if [ ! -f "$fam/family.json" ] || [ "$(ls "$fam"/shape*.obj 2>/dev/null | wc -l)" -lt "$maxn" ]; then
  rm -rf "$fam"
  "$TOOLS/qs-family" generate -n "$maxn" --faces 8000 --seed 1 -o "$fam" -q \
    || { echo "scale.sh: qs-family generate failed" >&2; exit 1; }
fi
rows=()
frows=()
for n in 1 2 4 8 16 32; do
  [ "$n" -le "$maxn" ] || break
  mapfile -t shapes < <(ls "$fam"/shape*.obj | sort | head -n "$n")
  echo "== family of $n" >&2
  r=$(run "family_$n" "${shapes[@]}")
  rows+=("family_$n $n $r")
  frows+=("$n $r")
done
table "Generated families dissected together (qs-family generate, 8000 faces a mesh)" meshes "${rows[@]}"
echo
echo "per mesh (CPU; the union tree grows with N, so per mesh per patch is the flat figure):"
printf '%s\n' "${frows[@]}" | awk 'BEGIN { printf "%8s %16s %28s\n", "meshes", "CPU s per mesh", "CPU ms per mesh per patch" }
  $2 != "failed" && $5 > 0 { printf "%8d %16.3f %28.2f\n", $1, $3 / $1, 1000 * $3 / $1 / $5 }'

# 4. A mesh and its own re-tessellation, dissected as a pair (same pose: automatic seeds).
sizes="40000 80000 150000"
[ "$quick" = 1 ] && sizes=40000
rows=()
for fc in $sizes; do
  r=$M/elephant_$fc.obj
  if [ ! -f "$r" ]; then
    "$TOOLS/qs-family" retessellate "$MESHES/elephant_12k.obj" --faces "$fc" -o "$r" -q \
      || { echo "scale.sh: qs-family retessellate failed" >&2; exit 1; }
  fi
  echo "== elephant_12k + its re-tessellation to $fc faces" >&2
  rows+=("elephant+$fc $((fc + $(faces_of "$MESHES/elephant_12k.obj"))) $(run "pair_$fc" "$MESHES/elephant_12k.obj" "$r")")
done
table "A mesh and its re-tessellation as a pair (elephant_12k; faces of both)" faces "${rows[@]}"

# 5. One face re-tessellated twice (about 28k and 140k faces), dissected as a pair.
rows=()
pair=()
for fc in 24000 120000; do
  r=$M/max_planck_$fc.obj
  if [ ! -f "$r" ]; then
    "$TOOLS/qs-family" retessellate "$MESHES/max_planck_11k.obj" --faces "$fc" -o "$r" -q \
      || { echo "scale.sh: qs-family retessellate failed" >&2; exit 1; }
  fi
  pair+=("$r")
done
echo "== max_planck_11k re-tessellated to $(faces_of "${pair[0]}") and $(faces_of "${pair[1]}") faces" >&2
rows+=("max_planck_pair $(($(faces_of "${pair[0]}") + $(faces_of "${pair[1]}"))) $(run face_pair "${pair[@]}")")
table "One face re-tessellated twice, as a pair (max_planck_11k; faces of both)" faces "${rows[@]}"

# 6. Four generated 100k-face meshes dissected together (full set only).
if [ "$quick" = 0 ]; then
  fam=$M/family100k
  if [ ! -f "$fam/family.json" ] || [ "$(ls "$fam"/shape*.obj 2>/dev/null | wc -l)" -lt 4 ]; then
    rm -rf "$fam"
    "$TOOLS/qs-family" generate -n 4 --faces 100000 --seed 1 -o "$fam" -q \
      || { echo "scale.sh: qs-family generate failed" >&2; exit 1; }
  fi
  mapfile -t shapes < <(ls "$fam"/shape*.obj | sort | head -n 4)
  echo "== four 100k-face meshes" >&2
  table "Four generated meshes dissected together (qs-family generate, 100000 faces a mesh)" faces \
    "family100k_4 400000 $(run family100k_4 "${shapes[@]}")"
fi

# 7. Meshes in another pose (full set only): koala_100k and four shared meshes of 12k-29k faces
# (a cat, a body, the armadillo, an elephant), each posed as rigidly as possible with its pose
# re-tessellated to 140k faces (qs-family pose --seed 1 --retessellate --keep-shape), dissected
# as a pair with the landmarks the generator chose (the first mesh registered onto the other).
# "dissections": 2 where the first dissection folded and the set was dissected again with safer
# maps (the report's "fallback").
if [ "$quick" = 0 ]; then
  rows=()
  for stem in koala_100k cat_sumner_14k smpl_man_14k armadillo_29k elephant_12k; do
    posed=$M/${stem}_posed/posed
    if [ ! -f "${posed}_r.obj" ]; then
      mkdir -p "$M/${stem}_posed"
      "$TOOLS/qs-family" pose "$MESHES/$stem.obj" --seed 1 --retessellate --faces 140000 --keep-shape \
        -o "$posed.obj" -q || { echo "scale.sh: qs-family pose $stem failed" >&2; exit 1; }
    fi
    echo "== $stem against its pose re-tessellated to $(faces_of "${posed}_r.obj") faces" >&2
    r=$(run "${stem}_posed" "$MESHES/$stem.obj" "${posed}_r.obj" --landmarks "$posed.source.landmarks.json" \
      "${posed}_r.landmarks.json")
    n=1
    grep -q "(fallback: " "$OUT/runs/${stem}_posed.txt" 2>/dev/null && n=2
    rows+=("$stem $(faces_of "$MESHES/$stem.obj") $(faces_of "${posed}_r.obj") $r $n")
  done
  # Different meshes: no growth exponent.
  echo
  echo "Meshes against their poses re-tessellated to 140k faces, as pairs:"
  printf '%s\n' "${rows[@]}" | awk '
    BEGIN { printf "%-16s %9s %9s %9s %8s %8s %8s %12s\n", "mesh", "faces", "posed", "wall s", "CPU s", "peak MB",
                   "patches", "dissections" }
    { printf "%-16s %9s %9s %9s %8s %8s %8s %12s\n", $1, $2, $3, $4, $5, $6, $7, $4 == "failed" ? "-" : $8 }'
fi
