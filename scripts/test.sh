#!/usr/bin/env bash
# The README's second command: builds (if needed) and runs the whole test suite with CTest.
# Suites that need ../shared/data or a GPU report those tests as skipped where they are absent.
# As many tests run at once as there are cores (AT_TEST_JOBS=N sets it): each test has its own
# temporary folders, databases and PostgreSQL databases (tests/CMakeLists.txt).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest --output-on-failure --timeout 1200 -j "${AT_TEST_JOBS:-$(nproc)}" "$@"
