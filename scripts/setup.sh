#!/usr/bin/env bash
# Installs qs's build and test dependencies from Debian 12's packages.
# Idempotent and non-interactive; run as root (or with sudo available).
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libcgal-dev libeigen3-dev libopenmesh-dev libopenimageio-dev
  libtinygltf-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcpp-httplib-dev chromium
  liblemon-dev
  clang-16 libclang-rt-16-dev  # libFuzzer, ASan and UBSan for scripts/fuzz.sh (clang 14 lacks C++20 binding captures)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done

# node (with npm) runs the Khronos glTF validator; a machine that has one already keeps it.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  missing+=(nodejs npm)
fi

install_validator() {
  local dir="$(cd "$(dirname "$0")" && pwd)/validator"
  [ -f "$dir/node_modules/gltf-validator/index.js" ] && return 0
  echo "setup: installing the glTF validator (npm gltf-validator) into scripts/validator"
  # Without the npm registry the GLB checks are skipped (tests say so); everything else works.
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null 2>&1) ||
    echo "setup: warning: could not install gltf-validator; GLB validation will be skipped" >&2
}

# qs-studio's page: three.js (served locally, no CDN) and puppeteer-core (its browser tests).
install_studio_web() {
  local dir="$(cd "$(dirname "$0")/.." && pwd)/web/studio"
  [ -f "$dir/node_modules/three/build/three.module.js" ] && [ -d "$dir/node_modules/puppeteer-core" ] && return 0
  echo "setup: installing three.js and puppeteer-core (npm) into web/studio for qs-studio"
  # Without the npm registry the studio serves a page that says what is missing; browser tests skip.
  (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error >/dev/null 2>&1) ||
    echo "setup: warning: could not install web/studio's npm packages; qs-studio's page and browser tests will not work" >&2
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages already installed"
  install_validator
  install_studio_web
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi

echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
install_validator
install_studio_web
echo "setup: done"
