#!/usr/bin/env bash
# Builds test_cuda and growth_bench for the lent H200 (sm_90, no app) and packs them, stripped and
# gzipped, with a baseline's growth_bench and bench/growth_local_reset_on_gpu.sh into .gpu/lr/
# (git-ignored) of this checkout and of each DEST given (the device tool sends the session's
# checkout).   bash bench/pack_growth_local_reset.sh BASELINE_GROWTH_BENCH [DEST_CHECKOUT…]
# The device command is in growth_local_reset_on_gpu.sh's header; remove .gpu/lr afterwards.
set -euo pipefail
cd "$(dirname "$0")/.."
before=${1:?baseline growth_bench binary}
shift
cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DAT_BUILD_APP=OFF -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
ninja -C build-gpu -j2 test_cuda growth_bench
pack=.gpu/lr
rm -rf "$pack" && mkdir -p "$pack"
strip -o "$pack/test_cuda" build-gpu/tests/test_cuda && gzip -9 "$pack/test_cuda"
strip -o "$pack/growth_bench_after" build-gpu/bench/growth_bench && gzip -9 "$pack/growth_bench_after"
strip -o "$pack/growth_bench_before" "$before" && gzip -9 "$pack/growth_bench_before"
cp bench/growth_local_reset_on_gpu.sh "$pack/"
{ git rev-parse HEAD; git status --short -- cuda tests/cuda bench wdt; echo "before: $before"; } > "$pack/commit.txt"
for dest in "$@"; do
  rm -rf "${dest:?}/$pack" && mkdir -p "$dest/.gpu" && cp -r "$pack" "$dest/.gpu/"
  (cd "$dest" && git check-ignore -q "$pack") || { echo "$dest/$pack is not git-ignored there" >&2; exit 1; }
done
du -sh "$pack"
