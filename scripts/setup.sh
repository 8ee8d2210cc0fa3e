#!/usr/bin/env bash
# The README's first command: installs the Debian packages, fetches the real scans that come from
# Debian packages, builds, labels them (the segment command on the kept seeds) and runs
# anatomy-tutor: on the course "The skull on CT" when the head CT is here, else on the built-in
# default course (the phantom's temporal bone). With no display it writes the course's first views.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# The real head CT (`skull`) comes from a Debian package; without it only its tests skip.
fetched=yes
bash scripts/fetch-scans.sh || { fetched=no; echo "setup: the skull CT is not fetched; the datasets and tests that need it say so"; }
bash scripts/build.sh
start=()
if [ "$fetched" = yes ] && bash scripts/label-scans.sh; then
  start=(--course skull)
fi
echo
echo "== anatomy-tutor ${start[*]:-(default course)} =="
./build/app/anatomy-tutor "${start[@]}"
