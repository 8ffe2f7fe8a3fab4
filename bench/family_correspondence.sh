#!/usr/bin/env bash
# Correspondence of generated families dissected together (beyond bench/correspondence.sh's
# fam4/fam8 at variation 1): families of 4-8 shapes up to the largest variation qs-family makes,
# each dissected with qs-dissect as a user would (landmarks beside the meshes), then measured with
# `qs-metro --correspondence` (shape00 against every other shape, chart map, per unit area).
#
#   usage: bench/family_correspondence.sh [OUT_DIR]   (default out/bench-family-correspondence)
#   env:   QS_TOOLS (default build/tools), SAMPLES (default 20000),
#          DISSECT_ARGS (extra qs-dissect options, e.g. "--no-refine-maps" or "--config FILE")
# Prints per family: shapes, variation, faces, dissection wall time, common patches, and over its
# pairs the mean of the mean / p95 / max errors, the worst max (% of B's diagonal), the share of
# A's area in the same patch on B, and the mean distance of B's patch corners from their exact place.
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/bench-family-correspondence}
TOOLS=${QS_TOOLS:-build/tools}
SAMPLES=${SAMPLES:-20000}
read -r -a EXTRA <<< "${DISSECT_ARGS:-}"
mkdir -p "$OUT"
# seed:shapes:variation:faces
FAMILIES=(11:6:1.0:6000 12:4:1.0:6000 13:5:1.8:6000 14:6:1.8:6000 17:6:1.8:6000 20:6:1.8:6000
          40:8:2.0:8000 41:8:2.0:8000 45:8:2.0:8000)
printf '%-22s %6s %7s %5s %5s %5s %6s %5s %s\n' family "time s" patches mean p95 max "worst" same corners
for f in "${FAMILIES[@]}"; do
  IFS=: read -r seed n var faces <<< "$f"
  d="$OUT/s$seed-n$n-v$var"
  if [ ! -f "$d/family.json" ]; then
    rm -rf "$d"
    "$TOOLS/qs-family" generate -n "$n" --seed "$seed" --variation "$var" --faces "$faces" --quiet -o "$d" || exit 1
  fi
  t0=$(date +%s.%N)
  "$TOOLS/qs-dissect" "$d"/shape*.obj -o "$d/dissection" --quiet "${EXTRA[@]}" > "$d/dissect.log" 2>&1
  rc=$?
  t1=$(date +%s.%N)
  if [ $rc -ne 0 ]; then
    echo "$d: qs-dissect exit $rc ($(tail -n1 "$d/dissect.log"))"
    continue
  fi
  "$TOOLS/qs-metro" --correspondence "$d/dissection" --samples "$SAMPLES" --json -o "$d/corr.json" > "$d/metro.log" 2>&1 ||
    { echo "$d: measuring failed: $(tail -n1 "$d/metro.log")"; continue; }
  python3 - "$d/corr.json" "seed $seed, n $n, v $var" "$t0" "$t1" <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); P = d["pairs"]
avg = lambda k: sum(p["dissection"][k] for p in P) / len(P)
print("%-22s %6.2f %7d %5.2f %5.2f %5.2f %6.2f %4.1f%% %5.2f" % (
    sys.argv[2], float(sys.argv[4]) - float(sys.argv[3]), d["patches"], avg("mean_percent"), avg("p95_percent"),
    avg("max_percent"), max(p["dissection"]["max_percent"] for p in P),
    100 * sum(p["same_patch_share"] for p in P) / len(P),
    sum(p["corner_distance_mean_percent"] for p in P) / len(P)))
PY
done
