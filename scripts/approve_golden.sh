#!/usr/bin/env bash
# Re-approves the render golden images: renders them with the current code and presets and writes
# them to tests/render/golden/. Look at the result (git diff shows which changed) before committing.
#   scripts/approve_golden.sh [BUILD_DIR]      (default: build)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
ninja -C "$build" -j2 test_render
AT_APPROVE_GOLDEN=1 "$build/tests/test_render" --test-case="Golden renders*" --success=false
git -C "$root" status --short tests/render/golden
