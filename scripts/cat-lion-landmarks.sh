#!/usr/bin/env bash
# Writes landmark files for the cat/lion pair of ../shared/meshes from cat_lion_markers.yml:
# 4 markers on a belt around the torso as seeds (mid back, left hind quarters, belly, right hind
# quarters), every other marker as a feature named by its comment, except the two that the seed
# loops leave on different sides ("left/right back leg to belly").
#   usage: scripts/cat-lion-landmarks.sh [MARKERS_YML] [OUTDIR]
set -euo pipefail
yml=${1:-"$(dirname "$0")/../../shared/meshes/cat_lion_markers.yml"}
out=${2:-out/cat_lion}
mkdir -p "$out"
for side in 1 2; do
  name=$([ $side = 1 ] && echo cat_sumner_14k || echo lion_sumner_10k)
  awk -v side=$side '
    match($0, /"[0-9]+:[0-9]+"/) {
      split(substr($0, RSTART + 1, RLENGTH - 2), ids, ":")
      c = $0; sub(/^[^#]*#[ \t]*/, "", c); sub(/[ \t]+$/, "", c)
      if (c == "mid back") s[0] = ids[side]
      else if (c == "left hind quarters") s[1] = ids[side]
      else if (c == "belly") s[2] = ids[side]
      else if (c == "right hind quarters") s[3] = ids[side]
      else if (c != "left back leg to belly" && c != "right back leg to belly") { n++; f[n] = "    \"" c "\": " ids[side] }
    }
    END {
      printf "{\n  \"seeds\": [%s, %s, %s, %s],\n  \"features\": {\n", s[0], s[1], s[2], s[3]
      for (i = 1; i <= n; i++) printf "%s%s\n", f[i], (i < n ? "," : "")
      printf "  }\n}\n"
    }' "$yml" > "$out/$name.landmarks.json"
  echo "wrote $out/$name.landmarks.json"
done
