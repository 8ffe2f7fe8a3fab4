#!/usr/bin/env bash
# Renders a GLB (or an OBJ) to a PNG the way a user's viewer shows it: three.js (MeshStandardMaterial
# as loaded, normal map, morph targets) in headless Chromium with software WebGL (SwiftShader).
# Framing is deterministic: an orthographic camera fitted to the shape's extent along --view.
#   usage: scripts/glb-view.sh MODEL.glb -o OUT.png [--size 512] [--view x,y,z] [--weights a,b]
#          [--time T] [--no-map] [--fit current|all] [--label TEXT] ...   (--help lists all)
# Needs: node, Chromium (Debian: apt-get install chromium) and scripts/glb-view/node_modules
# (cd scripts/glb-view && npm ci). Not part of scripts/setup.sh: CI does not need it.
# Exit codes: 0 ok, 1 usage, 2 the page failed (bad model or weights, no WebGL), 3 not installed.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)/glb-view"
command -v node >/dev/null || { echo "glb-view: node is not installed (Debian: apt-get install nodejs npm)" >&2; exit 3; }
chromium="${CHROMIUM:-/usr/bin/chromium}"
for a in "$@"; do [ "${prev:-}" = "--chromium" ] && chromium="$a"; prev="$a"; done
[ -x "$chromium" ] || { echo "glb-view: Chromium not found at $chromium: install it (Debian: sudo apt-get install chromium) or set CHROMIUM=/path/to/chrome" >&2; exit 3; }
[ -f "$here/node_modules/three/build/three.module.js" ] && [ -d "$here/node_modules/puppeteer-core" ] ||
  { echo "glb-view: three.js / puppeteer-core are not installed: run (cd $here && npm ci)" >&2; exit 3; }
exec node "$here/render.mjs" "$@"
