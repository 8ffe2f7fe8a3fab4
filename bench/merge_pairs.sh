#!/usr/bin/env bash
# Dissects four pairs (pig_4k + cow2_9k, horse_5k + camel_4k_fixed, cat_sumner +
# lion_sumner with their markers, the example's koala_7k + cat_16k) and runs qs-bench-merge on them.
#   usage: bench/merge_pairs.sh [MESH_DIR] [WORKDIR]   (defaults ../shared/meshes, out/bench-merge)
set -euo pipefail
cd "$(dirname "$0")/.."
meshes=${1:-../shared/meshes}
work=${2:-out/bench-merge}
tools=build/tools
mkdir -p "$work"
"$tools/qs-dissect" "$meshes/pig_4k.off" "$meshes/cow2_9k.off" -o "$work/pig_cow" -q
"$tools/qs-dissect" "$meshes/horse_5k.obj" "$meshes/camel_4k_fixed.obj" -o "$work/horse_camel" -q
bash scripts/cat-lion-landmarks.sh "$meshes/cat_lion_markers.yml" "$work/cat_lion_landmarks" >/dev/null
"$tools/qs-dissect" "$meshes/cat_sumner_14k.obj" "$meshes/lion_sumner_10k.obj" -q -o "$work/cat_lion" \
  --landmarks "$work/cat_lion_landmarks/cat_sumner_14k.landmarks.json" "$work/cat_lion_landmarks/lion_sumner_10k.landmarks.json"
"$tools/qs-dissect" examples/koala_7k.obj examples/cat_16k.obj -o "$work/koala_cat" -q
build/bench/qs-bench-merge "$work/pig_cow" "$work/horse_camel" "$work/cat_lion" "$work/koala_cat"
