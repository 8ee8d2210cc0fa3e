#!/usr/bin/env bash
# Configures and builds Anatomy Tutor into build/ (Release, Ninja). Re-running rebuilds only what changed.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${AT_JOBS:-$(nproc)}
# ccache when installed (scripts/install-deps.sh installs it): a rebuild after a fresh clone on the
# same machine, and the sanitizer build (scripts/sanitize.sh), reuse what was compiled before.
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
  # Paths below the checkout's folder are hashed relative to it, so another clone's build hits too.
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$(dirname "$PWD")}
fi
if [ ! -f build/build.ninja ]; then
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
fi
cmake --build build -j "$jobs"
