#!/usr/bin/env bash
# End-to-end check of the installed package: installs BUILD_DIR into a prefix, builds this
# project against it (find_package(qs)), runs qs_example and the installed qs-dissect + qs-remesh
# on the example set (spot, cat, koala with their landmarks) and on a pair of shared meshes
# (horse_5k, camel_4k_fixed; skipped when ../shared/meshes is absent), and compares every file
# they write byte for byte.
#   usage: examples/cpp/check.sh [BUILD_DIR [WORK_DIR]]   (defaults: build, a new temporary folder)
# BUILD_DIR must have the tools built. Exit 0: the same bytes; 1: a difference or a failed step.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="$(cd "${1:-$root/build}" && pwd)"
work="${2:-$(mktemp -d)}"
rm -rf "$work"
mkdir -p "$work"
work="$(cd "$work" && pwd)"
prefix="$work/prefix"

echo "== install $build -> $prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
echo "== build examples/cpp against it"
cmake -S "$root/examples/cpp" -B "$work/example-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/example-build" >/dev/null
example="$work/example-build/qs_example"

status=0
# same_tree A B: the same relative file names under A and B, and the same bytes in each.
same_tree() {
  local a=$1 b=$2 f n=0
  if ! diff <(cd "$a" && find . -type f | sort) <(cd "$b" && find . -type f | sort) >/dev/null; then
    echo "FAIL: $a and $b hold different files:" >&2
    diff <(cd "$a" && find . -type f | sort) <(cd "$b" && find . -type f | sort) >&2 || true
    return 1
  fi
  while IFS= read -r f; do
    cmp -s "$a/$f" "$b/$f" || { echo "FAIL: $a/$f and $b/$f differ" >&2; return 1; }
    n=$((n + 1))
  done < <(cd "$a" && find . -type f | sort)
  echo "   $n files identical"
}
# check_set NAME MESH...: the tools' folders against the program's.
check_set() {
  local name=$1
  shift
  local tools="$work/$name/tools" program="$work/$name/example"
  echo "== $name: $*"
  mkdir -p "$work/$name"
  local log="$work/$name/log.txt"
  if ! { "$prefix/bin/qs-dissect" "$@" -o "$tools/dissection" &&
         "$prefix/bin/qs-remesh" "$tools/dissection" --level 4 -o "$tools/remesh-L4" &&
         "$example" "$program" "$@"; } >"$log" 2>&1; then
    echo "FAIL: a program failed; its output:" >&2
    cat "$log" >&2
    status=1
    return
  fi
  same_tree "$tools" "$program" || status=1
}

cd "$root"
check_set examples examples/spot_2k.obj examples/cat_16k.obj examples/koala_7k.obj
shared="$root/../shared/meshes"
if [ -f "$shared/horse_5k.obj" ] && [ -f "$shared/camel_4k_fixed.obj" ]; then
  check_set horse_camel "$shared/horse_5k.obj" "$shared/camel_4k_fixed.obj"
else
  echo "== horse_camel: skipped (no $shared/horse_5k.obj and camel_4k_fixed.obj)"
fi
[ "$status" -eq 0 ] && echo "OK: qs_example wrote the same bytes as qs-dissect + qs-remesh"
exit "$status"
