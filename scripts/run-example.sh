#!/usr/bin/env bash
# The main job on the bundled examples: installs dependencies if missing, builds, and runs the
# pipeline on examples/. Today the pipeline is: read and validate every example mesh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
out=${1:-out/example}
mkdir -p "$out"
echo "== qs-inspect examples/*.obj"
build/tools/qs-inspect examples/*.obj
build/tools/qs-inspect --json examples/*.obj > "$out/inspect.json"
echo "== wrote $out/inspect.json"
