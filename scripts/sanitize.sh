#!/usr/bin/env bash
# The unit tests under AddressSanitizer + UBSan, in the clang tree ./build-fuzz (the fuzz
# targets' tree): the modules whose input parsers the fuzz targets reach (core, io, mesh, shapes,
# landmarks, param, image), not the tests of ../shared's meshes. QS_SANITIZE_ALL=1 adds the map
# refinement's (they build on the CGAL-heavy modules: about 8 minutes more on two cores).
set -euo pipefail
cd "$(dirname "$0")/.."
CC=clang-16 CXX=clang++-16 cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_FLAGS="-gline-tables-only" -DQS_SANITIZE=ON -DQS_BUILD_FUZZ=ON -DQS_BUILD_BENCH=OFF >/dev/null
asan_tests=(qs_core_tests qs_io_tests qs_mesh_tests qs_shapes_tests qs_landmarks_tests qs_param_tests qs_image_tests)
asan_labels='core|io|mesh|shapes|landmarks|param|image'
if [ "${QS_SANITIZE_ALL:-0}" = 1 ]; then
  asan_tests+=(qs_maprefine_tests)
  asan_labels+='|maprefine'
fi
cmake --build build-fuzz -j"$(nproc)" --target "${asan_tests[@]}"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-fuzz --output-on-failure -j"$(nproc)" -L "^(${asan_labels})$" -E '^SharedMeshes\.'
