#!/usr/bin/env bash
# Installs the Debian packages Anatomy Tutor builds and tests with. Idempotent: packages already
# present are skipped, so running it twice costs one dpkg query.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git ccache
  libsdl2-dev libimgui-dev
  libepoxy-dev libegl-dev libegl1-mesa-dev libgl-dev libgl1-mesa-dri libegl-mesa0
  libsqlite3-dev nlohmann-json3-dev
  libdcmtk-dev libopenjp2-7-dev libnifti2-dev zlib1g-dev libpng-dev
  doctest-dev libexpected-dev
  xvfb xauth
  python3-skimage
  libarchive-dev libplist-dev
  librsvg2-bin desktop-file-utils strace
  librsvg2-dev libcairo2-dev fonts-dejavu-core
  postgresql libpq-dev pgbouncer
  nettle-dev
  clang-14 libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
# Node.js and npm (scripts/xapi-validator.sh installs the xAPI validator the tests run with them);
# a Node.js that brings its own npm (NodeSource's) is kept.
if ! command -v node > /dev/null 2>&1 || ! command -v npm > /dev/null 2>&1; then
  for p in nodejs npm; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
fi

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
