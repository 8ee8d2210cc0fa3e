#!/usr/bin/env bash
# Labels the real scans that fetch-scans.sh fetched, with anatomy-tutor's own segment command, from
# the seeds kept in the repository (data/segmentations/<scan>/seeds.json). Today one: the skull CT,
# 24 structures grown from seeds, the bones kept to their tissue range (CPU, about half a minute). The label map and its names go beside the
# scan in the cache folder, where `anatomy-tutor ... skull` finds them:
#   ${XDG_CACHE_HOME:-~/.cache}/anatomy-tutor/scans/invesalius-examples/skull.labels.nii.gz (+ .names.json)
# The same seeds give the same labels bit for bit (tests/app/test_skull_course.cpp checks them).
# usage: label-scans.sh [ANATOMY_TUTOR]   (default build/app/anatomy-tutor)
# Exits 0 when the labels are written, 1 with one line saying why not (no scan: run fetch-scans.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/app/anatomy-tutor}
if [ ! -x "$bin" ]; then
  echo "label-scans: $bin is not built (run scripts/build.sh first)" >&2
  exit 1
fi
dest="${XDG_CACHE_HOME:-$HOME/.cache}/anatomy-tutor/scans/invesalius-examples"
if ! "$bin" info skull >/dev/null 2>&1; then
  echo "label-scans: skull: the scan is not here (run scripts/fetch-scans.sh)" >&2
  exit 1
fi
mkdir -p "$dest"
rm -f "$dest/skull.labels.nii.gz" "$dest/skull.labels.names.json"
tmp="$dest/skull.labels.part.nii.gz"
"$bin" segment skull --seeds data/segmentations/skull/seeds.json --method grow --backend cpu \
  --out "$tmp" --names "$dest/skull.labels.names.json" >/dev/null
mv "$tmp" "$dest/skull.labels.nii.gz"
count=$(grep -c '"value": [1-9]' data/segmentations/skull/seeds.json)
echo "label-scans: skull: $dest/skull.labels.nii.gz ($count structures from data/segmentations/skull/seeds.json)"
