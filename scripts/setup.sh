#!/usr/bin/env bash
# The README's first command: installs the Debian packages, builds, and runs anatomy-tutor on its
# built-in default course.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
echo
echo "== anatomy-tutor (default course) =="
./build/app/anatomy-tutor
