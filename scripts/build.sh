#!/usr/bin/env bash
# Configures and builds Anatomy Tutor into build/ (Release, Ninja). Re-running rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${AT_JOBS:-$(nproc)}
if [ ! -f build/build.ninja ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
fi
cmake --build build -j "$jobs"
