#!/usr/bin/env bash
# Runs the benchmarks and regenerates docs/benchmarks.md from what they print.
#
#   usage: scripts/bench-page.sh [--quick] [--only NAME,...] [--no-build] [--page-only] [MESH_DIR]
#          (default MESH_DIR ../shared/meshes)
#
#   --quick     the fast set (a few minutes on 2 cores): reading, dissection (single meshes, sets,
#               one generated family), remesh, bake, morph and merge. Without it the page also gets
#               the defaults over every shared mesh, the correspondence benchmarks and the DFI
#               benchmark (much longer: about an hour on 2 cores).
#   --no-build  use the programs already in ./build (default: build the targets it needs first).
#   --only L    run only the benchmarks named in the comma-separated list L (names: io, dissect,
#               dissect-set, family-sets, remesh, bake, morph, merge, scale, defaults, correspondence,
#               real-self-pairs, dfi); the others keep the outputs of their last run.
#   --page-only write the page from the outputs of the last run (out/bench-page/) without running.
#
# Each benchmark's full output is kept in out/bench-page/<name>.txt; the page shows every line that
# states a target, and each output in full, followed by docs/bench-notes/<name>.md where there is
# one (figures measured by hand). A benchmark that fails is listed as failed, with the tail of its
# output, and the script exits 1 after writing the page.
set -uo pipefail
cd "$(dirname "$0")/.."

quick=0
build=1
run=1
only=
meshes=../shared/meshes
only_next=0
for a in "$@"; do
  if [ "$only_next" = 1 ]; then only=$a; only_next=0; continue; fi
  case "$a" in
    --quick) quick=1 ;;
    --no-build) build=0 ;;
    --page-only) run=0; build=0 ;;
    --only) only_next=1 ;;
    --only=*) only=${a#--only=} ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) echo "bench-page.sh: unknown option $a (try --help)" >&2; exit 1 ;;
    *) meshes=$a ;;
  esac
done
[ -d "$meshes" ] || { echo "bench-page.sh: $meshes is not a folder of meshes" >&2; exit 3; }

out=out/bench-page
page=docs/benchmarks.md
bench=build/bench
mkdir -p "$out"

quick_targets=(qs-bench-io qs-bench-dissect qs-bench-dissect-set qs-bench-family-sets qs-bench-remesh
               qs-bench-bake qs-bench-morph qs-bench-merge qs-dissect qs-family)
full_targets=(qs-bench-defaults qs-bench-dfi qs-family qs-metro qs-remesh)
targets=("${quick_targets[@]}")
[ "$quick" = 1 ] || targets+=("${full_targets[@]}")
[ "$only_next" = 0 ] || { echo "bench-page.sh: --only needs a list of names" >&2; exit 1; }
if [ "$run" = 0 ] && [ ! -f "$out/load.txt" ]; then
  echo "bench-page.sh: --page-only needs the outputs of an earlier run in $out" >&2; exit 3
fi
if [ "$build" = 1 ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null || exit 1
  cmake --build build -j"$(nproc)" --target "${targets[@]}" || exit 1
fi

# name|title|what it measures|command (run from the repository root)
runs=(
  "io|Reading and validation|Read + validate every shared mesh, best of 5 runs.|$bench/qs-bench-io $meshes"
  "dissect|Dissection of single meshes|The default dissection of every shared mesh, against one sparse solve of the whole mesh (the floor: every tree level solves about the whole mesh once).|$bench/qs-bench-dissect $meshes"
  "dissect-set|Dissection of sets|Meshes dissected together (union quinary tree, feature alignment); one mesh repeated 1, 2, 4, 8 times.|$bench/qs-bench-dissect-set $meshes"
  "family-sets|Generated families|Families of 1-16 generated shapes (8000 faces each) dissected together, best of 3; t(N)/(N t(1)) = 1 is linear.|$bench/qs-bench-family-sets 1"
  "remesh|Remesh|Uniform levels 3-6, adaptive, and the default even level 5 of six meshes (area cap 0.15); error = Metro two-sided mean and max, % of the bounding-box diagonal.|$bench/qs-bench-remesh $meshes"
  "bake|Normal maps|Bake time per tile size (max_planck_11k, 34 patches), and the shading check on the heads: mean angle between the shaded and the original normal with and without the map.|$bench/qs-bench-bake $meshes"
  "morph|Morph output|100 frames of a 49,688-vertex morph written as OBJ and as binary PLY; a GLB with 8 morph targets; a 4096² frame normal map.|$bench/qs-bench-morph"
  "merge|Exact merge|The four pairs dissected at the defaults, then merged (qs-merge): sizes, crossings, slivers, time on 1 and 2 threads, exactness checks.|bash bench/merge_pairs.sh $meshes out/bench-page/merge"
)
# The scale benchmark: its quick set here, its full set (to 6M faces, families to 32) below.
if [ "$quick" = 1 ]; then
  runs+=("scale|Scale|qs-dissect as meshes grow (one mesh subdivided, fan caps, families dissected together, a mesh and its re-tessellation): wall and CPU time, peak memory, growth exponents; the quick set.|bash bench/scale.sh --quick $meshes out/bench-page/scale")
else
  runs+=("scale|Scale|qs-dissect as meshes grow (one mesh subdivided to 6M faces, fan caps, families of 1-32 dissected together, a mesh and its re-tessellation to 150k faces): wall and CPU time, peak memory, growth exponents.|bash bench/scale.sh $meshes out/bench-page/scale")
fi
if [ "$quick" = 0 ]; then
  runs+=(
    "defaults|Defaults on every shared mesh|The default dissection, then the default remesh at levels 4 and 5 and area-sized tiles: patches, level-5 error, small angles, vertex and texel spreads.|$bench/qs-bench-defaults $meshes default"
    "correspondence|Correspondence|Every pair dissected with qs-dissect as a user would, measured by qs-metro --correspondence against exact ground truth (% of B's diagonal), beside the similarity + nearest-point baseline.|bash bench/correspondence.sh $meshes out/bench-page/correspondence"
    "real-self-pairs|Real meshes against their own re-tessellation|18 shared meshes re-tessellated keeping their shape, landmarks at the principal axes' extremes; the ideal map is the identity.|env RETESS_ARGS=--keep-shape bash bench/real_self_pairs.sh $meshes out/bench-page/real-self-pairs"
    "dfi|Distance-field morph|qs-dfi at grid 150 as it runs by default: the genus-0 animal pairs (11 frames at even change, refined ends), then pairs of genus 0 to 2 (6 uniform frames); per frame components, genus, volume over the linear interpolation of the inputs', step from the frame before and time; per pair the same summed up, and the ends against the inputs.|bash bench/dfi.sh"
  )
fi

failed=()
[ "$run" = 1 ] && cut -d' ' -f1-3 /proc/loadavg > "$out/load.txt"
for r in "${runs[@]}"; do
  IFS='|' read -r name title what cmd <<< "$r"
  if [ "$run" = 0 ] || { [ -n "$only" ] && [[ ",$only," != *",$name,"* ]]; }; then
    [ -f "$out/$name.seconds" ] || { echo "not run" > "$out/$name.seconds"; : > "$out/$name.txt"; }
    [ "$(cat "$out/$name.seconds")" = failed ] && failed+=("$name")
    continue
  fi
  echo "bench-page: $name: $cmd" >&2
  start=$(date +%s)
  # shellcheck disable=SC2086
  if $cmd > "$out/$name.txt" 2>&1; then
    echo "$(( $(date +%s) - start ))" > "$out/$name.seconds"
  else
    echo "failed" > "$out/$name.seconds"
    failed+=("$name")
  fi
done
[ "$run" = 1 ] && cut -d' ' -f1-3 /proc/loadavg >> "$out/load.txt"

cpu=$(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | sed 's/.*: //')
if [ -n "$only" ]; then
  mode="benchmarks run one by one with \`--only\`; each section shows its own command and time"
elif [ "$quick" = 1 ]; then
  mode="the quick set, \`--quick\`; without it the script also runs the long benchmarks"
else
  mode="the full set; \`--quick\` runs only the fast part"
fi
{
  echo "# Benchmarks"
  echo
  echo "<!-- Generated by scripts/bench-page.sh; edit the script, not this page. -->"
  echo "This page is generated by \`bash scripts/bench-page.sh\` from what the benchmark programs print"
  echo "($mode). Release build, ${cpu:-unknown CPU}, $(nproc) cores,"
  if [ "$(wc -l < "$out/load.txt")" -ge 2 ]; then
    echo "load average $(head -1 "$out/load.txt" | cut -d' ' -f1) at the start and $(tail -1 "$out/load.txt" | cut -d' ' -f1) at the end of the last run;"
  else
    echo "load average $(tail -1 "$out/load.txt" | cut -d' ' -f1) at the end of the last run;"
  fi
  echo "times are wall clock and grow with the machine's load."
  echo "Programs and scripts:"
  echo "[developers](developers.md#benchmarks)."
  echo
  echo "## Targets"
  echo
  echo "Every line of the outputs below that states a target:"
  echo
  echo '```'
  for r in "${runs[@]}"; do
    IFS='|' read -r name title what cmd <<< "$r"
    grep -E -i 'target[: ]' "$out/$name.txt" 2>/dev/null | grep -v '^ *$' | sed "s/^ */$name: /"
  done
  echo '```'
  for r in "${runs[@]}"; do
    IFS='|' read -r name title what cmd <<< "$r"
    echo
    echo "## $title"
    echo
    echo "$what"
    echo
    secs=$(cat "$out/$name.seconds")
    if [ "$secs" = "not run" ]; then
      echo "Not run (\`$cmd\`)."
    elif [ "$secs" = failed ]; then
      echo "**Failed** (\`$cmd\`); the end of its output:"
      echo
      echo '```'
      tail -n 20 "$out/$name.txt"
      echo '```'
    else
      echo "\`$cmd\` ($secs s):"
      echo
      # Progress lines of the tools the scripts run are left out; the figures stay. Markdown
      # tables that a script prints are shown as tables, the other lines as printed.
      text=$(grep -v -E '^(== |bench-page:)' "$out/$name.txt" | grep -v '^|')
      if [ -n "$text" ]; then
        echo '```'
        echo "$text"
        echo '```'
      fi
      if grep -q '^|' "$out/$name.txt"; then
        echo
        grep '^|' "$out/$name.txt"
      fi
    fi
    # Figures measured by hand beside a benchmark (runs too long for the page, profiles) live in
    # docs/bench-notes/<name>.md and follow its output.
    if [ -f "docs/bench-notes/$name.md" ]; then
      echo
      cat "docs/bench-notes/$name.md"
    fi
  done
} > "$page.tmp" && mv "$page.tmp" "$page"

echo "bench-page: wrote $page (outputs in $out)" >&2
if [ "${#failed[@]}" -gt 0 ]; then
  echo "bench-page: failed: ${failed[*]}" >&2
  exit 1
fi
