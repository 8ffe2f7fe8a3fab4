#!/usr/bin/env bash
# The test command: installs dependencies if missing, builds, runs every test with CTest; then the
# sanitizer tree (clang, ASan + UBSan, ./build-fuzz): each fuzz target briefly and the fast unit
# tests (set QS_SKIP_SANITIZERS=1 to skip that part locally).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --dev
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j"$(nproc)"

if [ "${QS_SKIP_SANITIZERS:-0}" != 1 ]; then
  # Each fuzz target for 7 s on its seed corpus (about a minute in all); exits 1 on a finding.
  bash scripts/fuzz.sh 7
  # Under ASan + UBSan: the unit tests of the modules the fuzz targets already built (not the
  # tests of ../shared's meshes: the run above has them). The other modules' tests build on the
  # CGAL-heavy ones and take long under the sanitizers: QS_SANITIZE_ALL=1 adds the map refinement's.
  asan_tests=(qs_core_tests qs_io_tests qs_mesh_tests qs_shapes_tests qs_landmarks_tests qs_param_tests qs_image_tests)
  asan_labels='core|io|mesh|shapes|landmarks|param|image'
  if [ "${QS_SANITIZE_ALL:-0}" = 1 ]; then
    asan_tests+=(qs_maprefine_tests)
    asan_labels+='|maprefine'
  fi
  cmake --build build-fuzz -j"$(nproc)" --target "${asan_tests[@]}"
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-fuzz --output-on-failure -j"$(nproc)" -L "^(${asan_labels})$" \
      -E '^SharedMeshes\.'
fi
