#!/usr/bin/env bash
# Builds render_bench and growth_bench for the lent H200 (sm_90, no app: no SDL2, DCMTK, SQLite or
# PostgreSQL) and packs them, stripped and gzipped, with a baseline's render_bench and presets, the
# two libraries the lent machine lacks (libepoxy, libpng) and bench/render_frames_on_gpu.sh into
# .gpu/r31/ (git-ignored) of this checkout and of each DEST given (the device tool sends the
# session's checkout, which may be another worktree).
#   bash bench/pack_render_frames.sh BASELINE_SOURCE [DEST_CHECKOUT…]
# BASELINE_SOURCE: a source tree of the baseline commit (e.g. `git archive C | tar -x -C DIR`)
# with render_bench built in DIR/build-gpu (same cmake line as below). The device command is in
# render_frames_on_gpu.sh's header; remove .gpu/r31 afterwards.
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:?baseline source tree}
shift
cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DAT_BUILD_APP=OFF -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
ninja -C build-gpu -j2 render_bench growth_bench
pack=.gpu/r31
rm -rf "$pack" && mkdir -p "$pack/lib"
packBinary() { strip -o "$pack/$2" "$1" && gzip -9 "$pack/$2"; }
packBinary build-gpu/bench/render_bench render_bench
packBinary build-gpu/bench/growth_bench growth_bench_before
packBinary "$base/build-gpu/bench/render_bench" render_bench_base
for lib in $(ldd build-gpu/bench/render_bench "$base/build-gpu/bench/render_bench" | awk '/=> \// {print $3}' | sort -u); do
  case "$(basename "$lib")" in libepoxy*|libpng*) cp -L "$lib" "$pack/lib/" ;; esac
done
cp -r data/presets "$pack/presets"
cp -r "$base/data/presets" "$pack/presets_base"
cp bench/render_frames_on_gpu.sh "$pack/"
{ git rev-parse HEAD; git status --short -- bench render cuda wdt; echo "baseline: $base"; } > "$pack/commit.txt"
for dest in "$@"; do
  rm -rf "${dest:?}/$pack" && mkdir -p "$dest/.gpu" && cp -r "$pack" "$dest/.gpu/"
  (cd "$dest" && git check-ignore -q "$pack") || { echo "$dest/$pack is not git-ignored there" >&2; exit 1; }
done
du -sh "$pack"
