#!/usr/bin/env bash
# The DFI benchmark as qs-dfi runs by default (grid 150, --align similarity, frames at even
# change, end frames refined 3 times): the genus-0 animal pairs with 11 frames, then the pairs
# of other genus with 6 uniform frames (unrefined ends). Per frame and per pair: components,
# genus, volume against the linear interpolation, steps, ends, time (bench_dfi.cpp).
#
#   usage: bench/dfi.sh [--grid N] [--no-voting] [--arap]   (extra options go to both runs)
set -euo pipefail
cd "$(dirname "$0")/.."
bench=build/bench/qs-bench-dfi
[ -x "$bench" ] || { echo "dfi.sh: $bench is missing (cmake --build build --target qs-bench-dfi)" >&2; exit 3; }
"$bench" --retime --refine-ends 3 "$@" cat-koala horse-camel cow-pig
"$bench" --frames 6 "$@" sphere-torus horse-knot spot-eight femur-elephant eight-double-torus knot-double-torus
