#!/usr/bin/env bash
# Renders every structure of the skull CT's labels in context (its WDT preset) from the side that
# shows it best, and lays the renders out as one captioned contact sheet: the 3-D half of the labels'
# review (data/segmentations/skull/structures.json: review_state and review). Each caption is the
# structure's name and its review state. Needs the scan and its labels (scripts/fetch-scans.sh,
# scripts/label-scans.sh) and python3 (to read the review states).
#   scripts/skull-review-sheet.sh [BUILD_DIR]   (default: build)
# Environment: OUT (default docs/skull_labels_review.png), SIZE (default 192x144 per render),
# KEEP (a folder to keep the single renders in; default: a temporary folder, removed), REUSE=1 (with
# KEEP: lay out the renders already in KEEP instead of rendering again).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
app="$build/app/anatomy-tutor"
out="${OUT:-$root/docs/skull_labels_review.png}"
size="${SIZE:-192x144}"
catalogue="$root/data/segmentations/skull/structures.json"
[ -x "$app" ] || { echo "skull-review-sheet: $app not built (ninja -C $build anatomy-tutor)" >&2; exit 1; }
"$app" info skull >/dev/null 2>&1 || { echo "skull-review-sheet: the skull CT is not here (run scripts/fetch-scans.sh, then scripts/label-scans.sh)" >&2; exit 1; }
if [ -n "${KEEP:-}" ]; then panels="$KEEP"; mkdir -p "$panels"; else panels="$(mktemp -d)"; trap 'rm -rf "$panels"' EXIT; fi
export AT_DATA_DIR="${AT_DATA_DIR:-$root/data}"

# id and the view that shows it best
views="upper_teeth inferior
mandible lateral_right
coronoid_process_right lateral_right
coronoid_process_left lateral_left
maxilla anterior
zygomatic_arch_right lateral_right
zygomatic_arch_left lateral_left
nasal_cavity anterior
maxillary_sinus_right anterior
maxillary_sinus_left anterior
frontal_sinus anterior
sphenoid_sinus lateral_right
ethmoid_air_cells anterior
orbit_right anterior
orbit_left anterior
external_acoustic_meatus_right anterior
external_acoustic_meatus_left anterior
mastoid_air_cells_right lateral_right
mastoid_air_cells_left lateral_left
petrous_temporal_bone_right superior
petrous_temporal_bone_left superior
atlas_c1 inferior
axis_c2 posterior
temporal_line_left lateral_left"

args=()
while read -r id view; do
  [ "${REUSE:-0}" = 1 ] && [ -f "$panels/$id.png" ] ||
    "$app" render skull "$id" --mode wdt --view "$view" --size "$size" --out "$panels/$id.png" </dev/null >/dev/null
  caption="$(python3 - "$catalogue" "$root/data/segmentations/skull/seeds.json" "$id" "$view" <<'EOF'
import json, re, sys
entries = {e["id"]: e for e in json.load(open(sys.argv[1]))["structures"]}
names = {re.sub("[^a-z0-9]+", "_", l["name"].lower()).strip("_"): l["name"] for l in json.load(open(sys.argv[2]))["labels"]}
e = entries[sys.argv[3]]
print("%s\\n%s view: %s" % (names[e["id"]], sys.argv[4].replace("_", " "), e["review_state"].upper()))
EOF
)"
  args+=("$panels/$id.png" "$caption")
  echo "skull-review-sheet: $id ($view)"
done <<<"$views"
"$app" figure-sheet --out "$out" --columns 7 \
  --title "Skull CT labels in 3-D, each in context, with its review state" \
  "${args[@]}"
echo "skull-review-sheet: wrote $out"
