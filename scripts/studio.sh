#!/usr/bin/env bash
# Starts qs-studio (the local web page) on a folder of meshes, by default the bundled examples:
# installs dependencies if missing (scripts/setup.sh --studio), builds the tools, then runs
# build/tools/qs-studio FOLDER with any further arguments (e.g. --port 8421). Open the address
# it prints; Ctrl-C stops it.
#   usage: scripts/studio.sh [FOLDER] [qs-studio options]   (default FOLDER: examples)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --studio
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target qs-studio
folder=examples
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then folder=$1; shift; fi
exec build/tools/qs-studio "$folder" "$@"
