#!/usr/bin/env bash
# Runs on the GPU machine from the repository root with .gpu/ and .gl/ carried (see
# collect_gpu_binaries.sh): unpacks the GL loader packages, then runs the CUDA tests, the WDT
# benchmark (CPU and CUDA) and the render benchmark, writing logs and JSON lines to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export LD_LIBRARY_PATH=$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export AT_SHARED_DATA=$PWD/.gpu/shared
mkdir -p .gpu/shared/totalsegmentator && cp .gpu/data/* .gpu/shared/totalsegmentator/ 2>/dev/null
cd .gpu
nvidia-smi -L | tee "$OUT/machine.txt"
lscpu | grep -E "Model name|^CPU\(s\)" >> "$OUT/machine.txt"
run() { echo "== $*" | tee -a "$OUT/log.txt"; "$@" 2>&1 | tee -a "$OUT/log.txt"; }
run ./test_cuda
[ -x ./test_render ] && run ./test_render
run ./wdt_bench "$@" --data "$PWD/data" > "$OUT/wdt_bench.jsonl"
[ -x ./render_bench ] && run ./render_bench > "$OUT/render_bench.jsonl"
true
