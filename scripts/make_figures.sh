#!/usr/bin/env bash
# Regenerates the paper's figures on the built-in phantom into docs/figures/ with the shipped
# presets (data/presets). Each panel is one PNG; docs/figures/README.md says what each shows.
#   scripts/make_figures.sh [BUILD_DIR]        (default: build; needs build/app/anatomy-tutor)
# Environment: DATASET (default phantom, i.e. 256³), SIZE (default 448x448: panels stay under 300 KB), OUT (default docs/figures).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
app="$build/app/anatomy-tutor"
dataset="${DATASET:-phantom}"
size="${SIZE:-448x448}"
out="${OUT:-$root/docs/figures}"
mkdir -p "$out"
[ -x "$app" ] || { echo "make_figures: $app not built (ninja -C $build anatomy-tutor)" >&2; exit 1; }

render() {  # render FILE STRUCTURE ARGS...
  local file="$1" structure="$2"
  shift 2
  "$app" render "$dataset" "$structure" --size "$size" --presets "$root/data/presets" --out "$out/$file" "$@"
}

# Fig. 1: the lateral and the posterior semicircular canal, each in its WDT context.
render fig1_lateral_canal_wdt.png lateral_semicircular_canal --preset lateral_semicircular_canal_wdt
render fig1_posterior_canal_wdt.png posterior_semicircular_canal --preset posterior_semicircular_canal_wdt
# Fig. 2: the posterior canal and the facial nerve with more context (higher t).
render fig2_posterior_canal_wdt.png posterior_semicircular_canal --preset posterior_semicircular_canal_wdt --t 0.15
render fig2_facial_nerve_wdt.png facial_nerve --preset facial_nerve_wdt --context 1.1
# Fig. 4: the cochlea, weighted distance vs non-weighted distance, same transfer functions.
render fig4_cochlea_wdt.png cochlea --preset cochlea_wdt
render fig4_cochlea_unweighted.png cochlea --preset cochlea_unweighted
# Fig. 5: fuzzy boundary (Eqs. 4–5) vs hard edge.
render fig5_cochlea_fuzzy.png cochlea --preset cochlea_fuzzy
render fig5_cochlea_hard_edge.png cochlea --preset cochlea_hard_edge
# Fig. 6: the temporal line outlined on the bone surface.
render fig6_temporal_line_outline.png temporal_line --preset temporal_line_outline --context 1.1
# Fig. 7: distance lighting, the structure as the light source (Eq. 6).
render fig7_cochlea_lighting.png cochlea --preset cochlea_lighting
render fig7_lateral_canal_lighting.png lateral_semicircular_canal --preset lateral_semicircular_canal_lighting
