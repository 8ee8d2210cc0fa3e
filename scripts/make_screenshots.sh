#!/usr/bin/env bash
# Regenerates the README's screenshots: replays each UI script in docs/screenshots/*.json in the
# desktop app under Xvfb with Mesa (as the desktop tests do) and saves docs/screenshots/NAME.png.
# Needs a build (scripts/build.sh) and xvfb-run. Software GL renders each full-quality view in
# tens of seconds on a small machine.
set -euo pipefail
cd "$(dirname "$0")/.."
app=build/app/anatomy-tutor
[ -x "$app" ] || { echo "make_screenshots: build first (bash scripts/build.sh)" >&2; exit 1; }
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
for script in docs/screenshots/*.json; do
  name=$(basename "$script" .json)
  # A fresh database per view: lesson progress from one script does not show in the next.
  XDG_DATA_HOME="$scratch/$name" xvfb-run -a -s "-screen 0 1280x800x24" "$app" desktop --size 1280x720 \
    --db "$scratch/$name.db" --ui-script "$script" --screenshot "docs/screenshots/$name.png" > "$scratch/$name.log"
  echo "docs/screenshots/$name.png"
done
