#!/usr/bin/env bash
# Rewrites docs/guide/ui-script-actions.md from the UI-script actions' registration tables
# (app/src/desktop/script_actions_*.cpp) through the built program. test_app's
# "docs/guide/ui-script-actions.md is the registry's text" fails until this is run after a change.
# Usage: scripts/update-ui-script-docs.sh [BUILD_DIR]   (default build/)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
app="$build/app/anatomy-tutor"
[ -x "$app" ] || { echo "update-ui-script-docs: $app is not built (cmake --build $build --target anatomy-tutor)" >&2; exit 1; }
"$app" desktop --help-actions --markdown > docs/guide/ui-script-actions.md.tmp
mv docs/guide/ui-script-actions.md.tmp docs/guide/ui-script-actions.md
echo "docs/guide/ui-script-actions.md: $(grep -c '^| `' docs/guide/ui-script-actions.md) actions"
