#!/usr/bin/env bash
# Builds qs's libFuzzer targets with clang, AddressSanitizer and UBSan in ./build-fuzz, and runs
# each for a fixed time on a corpus seeded from fuzz/corpus/<target>.
#
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET ...]     (default: 600 s, every target)
#
# Targets: read_obj read_off read_ply read_stl landmarks chart dissection_json remesh_json
# map_json studio_request image.
# New inputs go to build-fuzz/corpus/<target>; a crash, leak, timeout (10 s) or out-of-memory
# (2 GB) is written to build-fuzz/findings/<target>/ and makes the script exit 1 after the
# remaining targets have run. One summary line per target: runs, seconds, corpus size, findings.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(read_obj read_off read_ply read_stl landmarks chart dissection_json remesh_json map_json studio_request image)

if ! command -v clang++-16 >/dev/null; then
  echo "fuzz: clang++-16 not found; run scripts/setup.sh (it installs clang-16 and libclang-rt-16-dev)" >&2
  exit 1
fi
extra=()
command -v ccache >/dev/null && extra+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CC=clang-16 CXX=clang++-16 cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="-gline-tables-only" -DQS_SANITIZE=ON -DQS_BUILD_FUZZ=ON -DQS_BUILD_BENCH=OFF \
  "${extra[@]}" >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]/#/fuzz_}"

status=0
for t in "${targets[@]}"; do
  corpus=build-fuzz/corpus/$t findings=build-fuzz/findings/$t
  mkdir -p "$corpus" "$findings"
  log=build-fuzz/fuzz_$t.log
  set +e
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "build-fuzz/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "fuzz/corpus/$t" >"$log" 2>&1
  rc=$?
  set -e
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  took=$(grep -o 'Done [0-9]* runs in [0-9]* second' "$log" | grep -o 'in [0-9]*' | grep -o '[0-9]*' || echo "$seconds")
  found=$(find "$findings" -type f | wc -l)
  echo "fuzz: $t: $runs runs in ${took} s, corpus $(find "$corpus" -type f | wc -l) files, findings $found (log $log)"
  if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
    status=1
    grep -m3 -E 'ERROR|SUMMARY|runtime error' "$log" >&2 || true
  fi
done
exit $status
