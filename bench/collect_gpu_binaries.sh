#!/usr/bin/env bash
# Builds the binaries that run on the lent GPU machine (Ubuntu, CUDA driver, none of our Debian
# libraries) and gathers them into .gpu/ (git-ignored) with the shared libraries they need that
# such a machine lacks, plus the small real CT used by the benchmarks. The GPU build leaves out
# the app, db, lessons and DICOM (AT_BUILD_APP=OFF), so no SDL2, DCMTK or SQLite is needed there.
#
#   bash bench/collect_gpu_binaries.sh        then, on the GPU machine (device tool, carry .gpu and .gl):
#   bash .gpu/run_on_gpu.sh                   (see that script; it writes results to $OUT)
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DAT_BUILD_APP=OFF -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
targets="test_cuda test_wdt wdt_bench"
# The list is read whole first: `grep -q` on the pipe would stop early and, under pipefail, a
# ninja killed by SIGPIPE made a present target look absent.
all_targets=$(ninja -C build-gpu -t targets all 2>/dev/null)
for t in wdt_cuda_bench growth_bench render_bench progressive_bench test_render test_segment; do
  if grep -q "^$t:" <<<"$all_targets"; then targets="$targets $t"; fi
done
ninja -C build-gpu -j2 $targets
rm -rf .gpu && mkdir -p .gpu/lib .gpu/data
for t in $targets; do
  f=$(find build-gpu -name "$t" -type f -perm -u+x | head -n1)
  cp "$f" .gpu/
done
# Libraries outside the base system that the binaries link (resolved here with ldd).
for t in $targets; do ldd ".gpu/$t"; done | awk '/=> \// {print $3}' | sort -u | while read -r lib; do
  case "$(basename "$lib")" in
    libepoxy*|libnifti*|libznz*|libpng*|libexpected*) cp -L "$lib" .gpu/lib/ ;;
  esac
done
if [ -d ../shared/data/totalsegmentator ]; then
  cp ../shared/data/totalsegmentator/{ct_small.nii.gz,seg_small.nii.gz,labels.json} .gpu/data/
fi
cp bench/run_on_gpu.sh bench/run_growth_on_gpu.sh .gpu/
cp -r data/presets .gpu/presets 2>/dev/null || true
# The render tests read presets and golden images below the source directory compiled into them;
# run_on_gpu.sh recreates that path from these copies when the machine lacks it.
cp -r tests/render/golden .gpu/golden
pwd > .gpu/source_dir.txt
du -sh .gpu
