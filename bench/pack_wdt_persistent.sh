#!/usr/bin/env bash
# Builds test_cuda and wdt_cuda_bench for the lent H200 (sm_90, no app; static CUDA runtime, so
# only the base system's libraries are needed there) and packs them, stripped and gzipped, with
# bench/wdt_persistent_on_gpu.sh into .gpu/wdt35/ (git-ignored) of this checkout and of each
# DEST given (the device tool sends the session's checkout, which may be another worktree).
#   bash bench/pack_wdt_persistent.sh [DEST_CHECKOUT…]
# then, on the device tool (carry .gpu), one call:
#   mkdir -p /tmp/b && for f in .gpu/wdt35/*.gz; do gunzip -c $f > /tmp/b/$(basename $f .gz); done;
#   chmod +x /tmp/b/*; bash .gpu/wdt35/wdt_persistent_on_gpu.sh /tmp/b 115   (or wdt_persistent_default_on_gpu.sh)
# Remove .gpu/wdt35 afterwards.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DAT_BUILD_APP=OFF -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
ninja -C build-gpu -j2 test_cuda wdt_cuda_bench growth_bench
pack=.gpu/wdt35
rm -rf "$pack" && mkdir -p "$pack"
for f in build-gpu/tests/test_cuda build-gpu/bench/wdt_cuda_bench build-gpu/bench/growth_bench; do
  strip -o "$pack/$(basename "$f")" "$f"
  gzip -9 "$pack/$(basename "$f")"
done
cp bench/wdt_persistent_on_gpu.sh bench/wdt_persistent_default_on_gpu.sh "$pack/"
git rev-parse HEAD > "$pack/commit.txt"
git status --short -- cuda tests/cuda bench >> "$pack/commit.txt"
for dest in "$@"; do
  rm -rf "$dest/$pack" && mkdir -p "$dest/.gpu" && cp -r "$pack" "$dest/.gpu/"
  (cd "$dest" && git check-ignore -q "$pack") || { echo "$dest/$pack is not git-ignored there" >&2; exit 1; }
done
du -sh "$pack"
