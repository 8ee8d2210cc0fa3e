#!/usr/bin/env bash
# Runs on the GPU machine from the repository root with .gpu/ and .gl/ carried (see
# collect_gpu_binaries.sh): unpacks the GL loader packages, then runs the CUDA, WDT and render
# tests, the WDT benchmark (CPU and CUDA) and the render benchmark (compute and fragment ray
# casters, default and one-voxel steps), writing logs and JSON lines to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export LD_LIBRARY_PATH=$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
# The benchmarks' real CT: wdt_bench reads DIR/totalsegmentator/ (--data DIR), the tests
# AT_SHARED_DATA/totalsegmentator/.
export AT_SHARED_DATA=$PWD/.gpu/shared
mkdir -p .gpu/shared/totalsegmentator && cp .gpu/data/* .gpu/shared/totalsegmentator/ 2>/dev/null
src=$(cat .gpu/source_dir.txt 2>/dev/null)
if [ -n "$src" ] && [ ! -e "$src" ]; then
  mkdir -p "$src/data" "$src/tests/render"
  ln -s "$PWD/.gpu/presets" "$src/data/presets"
  ln -s "$PWD/.gpu/golden" "$src/tests/render/golden"
fi
cd .gpu
nvidia-smi -L | tee "$OUT/machine.txt"
lscpu | grep -E "Model name|^CPU\(s\)" >> "$OUT/machine.txt"
run() { echo "== $*" | tee -a "$OUT/log.txt"; "$@" 2>&1 | tee -a "$OUT/log.txt"; echo "== exit ${PIPESTATUS[0]}" | tee -a "$OUT/log.txt"; }
run ./test_cuda
[ -x ./test_wdt ] && run ./test_wdt
[ -x ./test_render ] && run ./test_render
run ./wdt_bench "$@" --data "$AT_SHARED_DATA" > "$OUT/wdt_bench.jsonl"
if [ -x ./render_bench ]; then
  run ./render_bench --presets presets > "$OUT/render_bench.jsonl"
  run ./render_bench --presets presets --ray-caster fragment --frames 10 --warmup 2 --cycles 4 >> "$OUT/render_bench.jsonl"
  run ./render_bench --presets presets --step-voxels 1 --frames 50 --warmup 5 --cycles 6 --compare-step 1 \
    --images "$OUT" >> "$OUT/render_bench.jsonl"
fi
true
