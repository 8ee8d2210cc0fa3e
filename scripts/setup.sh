#!/usr/bin/env bash
# The README's first command: installs the Debian packages, fetches the real scans that come from
# Debian packages, builds, and runs anatomy-tutor on its built-in default course.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# The real head CT (`skull`) comes from a Debian package; without it only its tests skip.
bash scripts/fetch-scans.sh || echo "setup: the skull CT is not fetched; the datasets and tests that need it say so"
bash scripts/build.sh
echo
echo "== anatomy-tutor (default course) =="
./build/app/anatomy-tutor
