#!/usr/bin/env bash
# The test command: installs dependencies if missing, builds, runs every test with CTest; then
# builds the fuzz targets with clang, ASan and UBSan (./build-fuzz) and runs each briefly (set
# QS_SKIP_SANITIZERS=1 to skip that part locally). The unit tests under the sanitizers:
# scripts/sanitize.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --dev
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j"$(nproc)"

if [ "${QS_SKIP_SANITIZERS:-0}" != 1 ]; then
  # Each fuzz target for 7 s on its seed corpus (about a minute in all); exits 1 on a finding.
  bash scripts/fuzz.sh 7
fi
