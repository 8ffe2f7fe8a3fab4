#!/usr/bin/env bash
# Runs the Khronos glTF validator (npm package gltf-validator, installed by scripts/setup.sh into
# scripts/validator/node_modules) on GLB / glTF files. Exit 0: no errors in any file; 1: a file
# has errors; 2: usage or i/o; 3: node or the validator is not installed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
command -v node >/dev/null || { echo "validate-gltf: node is not installed (run scripts/setup.sh)" >&2; exit 3; }
[ -f "$here/validator/node_modules/gltf-validator/index.js" ] ||
  { echo "validate-gltf: gltf-validator is not installed (run scripts/setup.sh)" >&2; exit 3; }
exec node "$here/validator/validate.js" "$@"
