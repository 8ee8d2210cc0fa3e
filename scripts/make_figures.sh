#!/usr/bin/env bash
# Regenerates the paper's figures into docs/figures/: panels on the built-in phantom with the shipped
# presets (data/presets), panels on the real abdominal CT in ../shared/data (read from there, never
# copied; presets derived from its intensities, skipped with a note when the folder is absent), and
# one captioned sheet per paper figure (sheet_fig*.png) built from them. docs/figures/README.md says
# what each shows.
#   scripts/make_figures.sh [BUILD_DIR]        (default: build; needs build/app/anatomy-tutor)
# Environment: DATASET (default phantom, i.e. 256³), SIZE (default 448x448: panels stay under 300 KB),
# OUT (default docs/figures), SHARED_DATA (default ../shared/data beside the repository).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
app="$build/app/anatomy-tutor"
dataset="${DATASET:-phantom}"
size="${SIZE:-448x448}"
out="${OUT:-$root/docs/figures}"
mkdir -p "$out"
[ -x "$app" ] || { echo "make_figures: $app not built (ninja -C $build anatomy-tutor)" >&2; exit 1; }

shared="${SHARED_DATA:-$root/../shared/data}"
ct="$shared/totalsegmentator"

render() {  # render FILE STRUCTURE ARGS...
  local file="$1" structure="$2"
  shift 2
  "$app" render "$dataset" "$structure" --size "$size" --presets "$root/data/presets" --out "$out/$file" "$@"
}
render_ct() {  # render_ct FILE STRUCTURE ARGS...: the real abdominal CT, presets derived from its HU
  local file="$1" structure="$2"
  shift 2
  "$app" render "$ct/ct_small.nii.gz" "$structure" --labels "$ct/seg_small.nii.gz" --names "$ct/labels.json" \
    --size "$size" --presets "$root/data/presets" --out "$out/$file" "$@"
}
render_skull() {  # render_skull FILE STRUCTURE ARGS...: the skull CT (scripts/fetch-scans.sh), derived presets
  local file="$1" structure="$2"
  shift 2
  "$app" render skull "$structure" --size "$size" --presets "$root/data/presets" --out "$out/$file" "$@"
}
sheet() {  # sheet FILE TITLE PANEL CAPTION ...: panels missing (no real CT here) are left out
  local file="$1" title="$2"
  shift 2
  local args=()
  while [ $# -ge 2 ]; do
    [ -f "$out/$1" ] && args+=("$out/$1" "$2")
    shift 2
  done
  "$app" figure-sheet --out "$out/$file" --title "$title" "${args[@]}"
}

# Fig. 1: the lateral and the posterior semicircular canal, each in its WDT context.
render fig1_lateral_canal_wdt.png lateral_semicircular_canal --preset lateral_semicircular_canal_wdt
render fig1_posterior_canal_wdt.png posterior_semicircular_canal --preset posterior_semicircular_canal_wdt
# Fig. 2: the posterior canal and the facial nerve with more context (higher t).
render fig2_posterior_canal_wdt.png posterior_semicircular_canal --preset posterior_semicircular_canal_wdt --t 0.3
render fig2_facial_nerve_wdt.png facial_nerve --preset facial_nerve_wdt --context 1.1
# Fig. 4: the cochlea, weighted distance vs non-weighted distance, same transfer functions.
render fig4_cochlea_wdt.png cochlea --preset cochlea_wdt --margin 2.6
render fig4_cochlea_unweighted.png cochlea --preset cochlea_unweighted --margin 2.6
# Fig. 5: fuzzy boundary (Eqs. 4–5) vs hard edge.
render fig5_cochlea_fuzzy.png cochlea --preset cochlea_fuzzy
render fig5_cochlea_hard_edge.png cochlea --preset cochlea_hard_edge
# Fig. 6: the temporal line outlined on the bone surface.
render fig6_temporal_line_outline.png temporal_line --preset temporal_line_outline --context 1.1
# Fig. 7: distance lighting, the structure as the light source (Eq. 6).
render fig7_cochlea_lighting.png cochlea --preset cochlea_lighting
render fig7_lateral_canal_lighting.png lateral_semicircular_canal --preset lateral_semicircular_canal_lighting

# The same looks on the real abdominal CT (3 mm voxels): the L1 vertebra and the right kidney.
if [ -f "$ct/ct_small.nii.gz" ]; then
  render_ct ct_fig1_l1_wdt.png vertebrae_l1 --mode wdt --view anterior
  render_ct ct_fig2_l1_wdt_t03.png vertebrae_l1 --mode wdt --view anterior --t 0.3
  render_ct ct_fig2_spinal_cord_wdt.png spinal_cord --mode wdt --view posterior
  render_ct ct_fig4_kidney_wdt.png kidney_right --mode wdt --view anterior
  render_ct ct_fig4_kidney_unweighted.png kidney_right --mode unweighted --view anterior
  render_ct ct_fig5_l1_fuzzy.png vertebrae_l1 --mode fuzzy --view anterior
  render_ct ct_fig6_l1_outline.png vertebrae_l1 --mode outline --view anterior
  render_ct ct_fig7_l1_lighting.png vertebrae_l1 --mode lighting --view anterior
else
  echo "make_figures: $ct/ct_small.nii.gz not found: real-CT panels left out" >&2
fi

# The skull CT (1 mm head CT, labels from scripts/label-scans.sh), presets derived from its HU; the
# distance unit from each field (render/field_scale.h), the headrest left out (derived_preset.h).
if "$app" structures skull >/dev/null 2>&1; then
  render_skull skull_fig1_ear_canal_wdt.png external_acoustic_meatus_right --mode wdt --view anterior
  render_skull skull_fig1_frontal_sinus_wdt.png frontal_sinus --mode wdt --view anterior
  render_skull skull_fig2_ear_canal_wdt_t03.png external_acoustic_meatus_right --mode wdt --view anterior --t 0.3
  render_skull skull_fig2_frontal_sinus_wdt_t1.png frontal_sinus --mode wdt --view anterior --t 1
  render_skull skull_fig4_ear_canal_wdt.png external_acoustic_meatus_right --mode wdt --view anterior --margin 2.6
  render_skull skull_fig4_ear_canal_unweighted.png external_acoustic_meatus_right --mode unweighted --view anterior --margin 2.6
  render_skull skull_fig4_maxillary_sinus_wdt.png maxillary_sinus_right --mode wdt --view anterior --margin 2.6
  render_skull skull_fig4_maxillary_sinus_unweighted.png maxillary_sinus_right --mode unweighted --view anterior --margin 2.6
  render_skull skull_fig5_mandible_fuzzy.png mandible --mode fuzzy --view anterior
  render_skull skull_fig5_mandible_bare.png mandible --mode bare --view anterior
  render_skull skull_fig6_zygomatic_arch_outline.png zygomatic_arch_left --mode outline --view lateral_left --margin 2.6
  render_skull skull_fig6_temporal_line_outline.png temporal_line_left --mode outline --view lateral_left
  render_skull skull_fig7_zygomatic_arch_lighting.png zygomatic_arch_left --mode lighting --view lateral_left --margin 2.6
else
  echo "make_figures: the skull CT is not fetched (scripts/fetch-scans.sh): skull sheets left out" >&2
fi

# One sheet per paper figure.
sheet sheet_fig1.png "Fig. 1 - WDT context around the structure" \
  fig1_lateral_canal_wdt.png "Phantom: lateral semicircular canal from above" \
  fig1_posterior_canal_wdt.png "Phantom: posterior canal from the side (lateral mastoid cut away)" \
  ct_fig1_l1_wdt.png "Real CT: L1 vertebra from the front, derived preset"
sheet sheet_fig2.png "Fig. 2 - more context: t = 0.3, and a long structure" \
  fig2_posterior_canal_wdt.png "Phantom: posterior canal, t = 0.3" \
  fig2_facial_nerve_wdt.png "Phantom: facial nerve with air cells and canals (lateral mastoid cut away)" \
  ct_fig2_l1_wdt_t03.png "Real CT: L1 vertebra, t = 0.3" \
  ct_fig2_spinal_cord_wdt.png "Real CT: spinal cord from behind"
sheet sheet_fig4.png "Fig. 4 - weighted vs non-weighted distance, same TFs" \
  fig4_cochlea_wdt.png "Phantom: cochlea, WDT" \
  fig4_cochlea_unweighted.png "Phantom: cochlea, non-weighted" \
  ct_fig4_kidney_wdt.png "Real CT: right kidney, WDT" \
  ct_fig4_kidney_unweighted.png "Real CT: right kidney, non-weighted"
sheet sheet_fig5.png "Fig. 5 - fuzzy boundary vs hard edge" \
  fig5_cochlea_fuzzy.png "Phantom: cochlea, fuzzy" \
  fig5_cochlea_hard_edge.png "Phantom: cochlea, hard edge" \
  ct_fig5_l1_fuzzy.png "Real CT: L1 vertebra, fuzzy"
sheet sheet_fig6.png "Fig. 6 - a band of constant weighted distance on the bone" \
  fig6_temporal_line_outline.png "Phantom: temporal line outlined" \
  ct_fig6_l1_outline.png "Real CT: L1 vertebra from the front; the band falls on the neighbouring vertebrae and ribs"
sheet sheet_fig7.png "Fig. 7 - the structure lights the bone (Eq. 6)" \
  fig7_cochlea_lighting.png "Phantom: cochlea as the light" \
  fig7_lateral_canal_lighting.png "Phantom: lateral canal as the light" \
  ct_fig7_l1_lighting.png "Real CT: L1 vertebra as the light"

# The same figures on the skull CT, one sheet each.
sheet sheet_skull_fig1.png "Fig. 1 on the skull CT - context near the structure, fading with weighted distance" \
  skull_fig1_ear_canal_wdt.png "Right ear canal from the front: the temporal bone around it, the rest fades" \
  skull_fig1_frontal_sinus_wdt.png "Frontal sinus from the front: its bony walls, the face fades"
sheet sheet_skull_fig2.png "Fig. 2 on the skull CT - more context with the slider t" \
  skull_fig2_ear_canal_wdt_t03.png "Right ear canal, t = 0.3: more of the skull as faint context" \
  skull_fig2_frontal_sinus_wdt_t1.png "Frontal sinus, t = 1: all bone in view"
sheet sheet_skull_fig4.png "Fig. 4 on the skull CT - weighted vs non-weighted distance, same TFs" \
  skull_fig4_maxillary_sinus_wdt.png "Right maxillary sinus, WDT: reaches through its opening to the nasal cavity and ethmoid cells" \
  skull_fig4_maxillary_sinus_unweighted.png "Right maxillary sinus, non-weighted: a cloud around it" \
  skull_fig4_ear_canal_wdt.png "Right ear canal, WDT: reaches along the bone connected to it" \
  skull_fig4_ear_canal_unweighted.png "Right ear canal, non-weighted: a ball around it"
sheet sheet_skull_fig5.png "Fig. 5 on the skull CT - fuzzy boundary vs the hard edge" \
  skull_fig5_mandible_fuzzy.png "Mandible, fuzzy: its colour fades into the neighbouring bone" \
  skull_fig5_mandible_bare.png "Mandible, hard edge (the segment alone)"
sheet sheet_skull_fig6.png "Fig. 6 on the skull CT - a band of constant weighted distance on the bone" \
  skull_fig6_temporal_line_outline.png "Left temporal line (the paper's landmark): a band on each side of it along the skull" \
  skull_fig6_zygomatic_arch_outline.png "Left zygomatic arch: a band on the lateral skull around it"
sheet sheet_skull_fig7.png "Fig. 7 on the skull CT - a small bone lights the bone near it (Eq. 6)" \
  skull_fig7_zygomatic_arch_lighting.png "Left zygomatic arch as the light"
