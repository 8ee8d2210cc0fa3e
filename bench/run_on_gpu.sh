#!/usr/bin/env bash
# Runs on the GPU machine from the repository root with .gpu/ and .gl/ carried (see
# collect_gpu_binaries.sh): unpacks the GL loader packages, then runs the CUDA and GL tests, the
# WDT benchmark on the GPU and the render benchmark, writing logs and JSON lines to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export LD_LIBRARY_PATH=$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
mkdir -p .gpu/shared/data/totalsegmentator && cp .gpu/data/* .gpu/shared/data/totalsegmentator/
export AT_SHARED_DATA=$PWD/.gpu/shared/data
cd .gpu
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$OUT/machine.txt" 2>&1
log() { echo "== $*" >> "$OUT/tests.log"; "$@" >> "$OUT/tests.log" 2>&1; echo "   exit $?" >> "$OUT/tests.log"; }
log ./test_cuda
log ./test_wdt
log ./test_render -tce='*olden*'
./wdt_bench --sizes 128,256,512 --backends cuda --repeats 10 --data "$PWD/data" > "$OUT/wdt_bench_cuda.jsonl" 2> "$OUT/wdt_bench.err"
./render_bench --size 1920x1080 --volume 512 --hover-volume 256 --frames 30 --warmup 5 --cycles 16 --presets "$PWD/presets" > "$OUT/render_bench.jsonl" 2> "$OUT/render_bench.err"
tail -n 3 "$OUT/tests.log"
cat "$OUT/render_bench.jsonl" | head -n 3
true
