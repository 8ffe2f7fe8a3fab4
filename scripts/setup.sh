#!/usr/bin/env bash
# Installs what qs needs from Debian 12's packages. Idempotent and non-interactive; run as root
# (or with sudo available).
#   usage: scripts/setup.sh [--python] [--studio] [--dev]
#   (none)    build and run: compiler, CMake, Ninja, the libraries qs links, and node with the
#             Khronos glTF validator (scripts/validate-gltf.sh) that scripts/run-example.sh runs
#   --python  adds pybind11, Python's headers and numpy: scripts/build.sh then builds the Python
#             module qs
#   --studio  adds web/studio's npm packages (three.js, which qs-studio's page loads)
#   --dev     adds what scripts/test.sh needs: the --python and --studio parts, GoogleTest/GoogleMock,
#             pytest (the Python module's tests), clang-16 with its runtime (libFuzzer, ASan, UBSan for scripts/fuzz.sh),
#             Chromium and web/studio's npm packages (puppeteer-core drives the studio's browser tests)
# What each package is for, and their licences: docs/packaging.md.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"

python=0
studio=0
dev=0
for a in "$@"; do
  case "$a" in
    --python) python=1 ;;
    --studio) studio=1 ;;
    --dev) dev=1; studio=1; python=1 ;;
    -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "setup: unknown argument '$a' (usage: scripts/setup.sh [--python] [--studio] [--dev])" >&2; exit 2 ;;
  esac
done

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libcgal-dev libpng-dev libopenexr-dev libtinygltf-dev nlohmann-json3-dev
  libcli11-dev liblemon-dev libcpp-httplib-dev
  ca-certificates  # npm's downloads
)
if [ "$python" = 1 ]; then
  packages+=(pybind11-dev python3-dev python3-numpy)  # the Python module qs
fi
if [ "$dev" = 1 ]; then
  packages+=(
    libgtest-dev libgmock-dev
    python3-pytest
    clang-16 libclang-rt-16-dev  # clang 14 lacks C++20 binding captures
    chromium
  )
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
# node runs the glTF validator, npm installs web/studio's packages; a machine that has them
# already (from any packaging) keeps them.
command -v node >/dev/null || missing+=(nodejs)
command -v npm >/dev/null || missing+=(npm)

if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  # --force-unsafe-io: dpkg does not fsync each unpacked file (as in Debian's container images);
  # about a third of the installation's time on a fresh machine (docs/packaging.md).
  $sudo apt-get install -y -qq --no-install-recommends -o Dpkg::Options::=--force-unsafe-io "${missing[@]}" >/dev/null
fi

# The Khronos glTF validator (npm package gltf-validator, one file of JavaScript and no
# dependencies) into scripts/validator/node_modules, as package-lock.json pins it.
# Without the npm registry the GLB checks are skipped (tests say so); everything else works.
install_validator() {
  local dir="$here/validator"
  [ -f "$dir/node_modules/gltf-validator/index.js" ] && return 0
  echo "setup: installing the glTF validator (gltf-validator) into scripts/validator"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null 2>&1) && return 0
  echo "setup: warning: could not install gltf-validator; GLB validation will be skipped" >&2
}

# web/studio's npm packages: three.js (qs-studio's page, served locally) and puppeteer-core (its
# browser tests). Without the npm registry the studio serves a page that says what is missing.
install_studio_web() {
  local dir="$here/../web/studio"
  [ -f "$dir/node_modules/three/build/three.module.js" ] && [ -d "$dir/node_modules/puppeteer-core" ] && return 0
  echo "setup: installing three.js and puppeteer-core (npm) into web/studio"
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null 2>&1) ||
    echo "setup: warning: could not install web/studio's npm packages; qs-studio's page and browser tests will not work" >&2
}

install_validator
if [ "$studio" = 1 ]; then
  install_studio_web
fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
else
  echo "setup: done"
fi
