#!/usr/bin/env bash
# The README's second command: builds (if needed) and runs the whole test suite with CTest.
# Suites that need ../shared/data or a GPU report those tests as skipped where they are absent.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest --output-on-failure --timeout 1200 "$@"
