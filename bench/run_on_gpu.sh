#!/usr/bin/env bash
# Runs on the GPU machine from the repository root with .gpu/ and .gl/ carried (see
# collect_gpu_binaries.sh): unpacks the GL loader packages, then runs the CUDA, WDT and GL tests,
# the WDT benchmark on the GPU and the render benchmark (compute ray caster at the default and a
# one-voxel step, with the image difference between them, and the fragment ray caster), writing
# logs and JSON lines to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
export LD_LIBRARY_PATH=$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
mkdir -p .gpu/shared/data/totalsegmentator && cp .gpu/data/* .gpu/shared/data/totalsegmentator/
export AT_SHARED_DATA=$PWD/.gpu/shared/data
# The render tests read presets and golden images below the source directory compiled into them:
# recreate that path from the copies in .gpu/ when this machine lacks it.
src=$(cat .gpu/source_dir.txt 2>/dev/null)
if [ -n "$src" ] && [ ! -e "$src" ]; then
  mkdir -p "$src/data" "$src/tests/render"
  ln -s "$PWD/.gpu/presets" "$src/data/presets"
  ln -s "$PWD/.gpu/golden" "$src/tests/render/golden"
fi
cd .gpu
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$OUT/machine.txt" 2>&1
log() { echo "== $*" >> "$OUT/tests.log"; "$@" >> "$OUT/tests.log" 2>&1; echo "   exit $?" >> "$OUT/tests.log"; }
log ./test_cuda
log ./test_wdt
log ./test_render
# wdt_bench reads DIR/totalsegmentator/ (--data DIR).
./wdt_bench --sizes 128,256,512 --backends cuda --repeats 10 --data "$PWD/shared/data" > "$OUT/wdt_bench_cuda.jsonl" 2> "$OUT/wdt_bench.err"
# Grow from seeds (8 labels on the phantom): the GPU at 128³–512³, the CPU engine beside it at 256³.
if [ -x ./growth_bench ]; then
  ./growth_bench --sizes 128,256,512 --backends cuda --reps 5 --check-max 256 > "$OUT/growth_bench_cuda.jsonl" 2> "$OUT/growth_bench.err"
  ./growth_bench --sizes 256 --backends cpu --reps 1 --check-max 0 > "$OUT/growth_bench_cpu.jsonl" 2>> "$OUT/growth_bench.err"
fi
rb() { ./render_bench --size 1920x1080 --volume 512 --hover-volume 256 --presets "$PWD/presets" "$@" >> "$OUT/render_bench.jsonl" 2>> "$OUT/render_bench.err"; }
rb --frames 30 --warmup 5 --cycles 16 --compare-step 1 --images "$OUT"
rb --frames 30 --warmup 5 --cycles 6 --step-voxels 1
rb --frames 5 --warmup 1 --cycles 3 --ray-caster fragment
# 4K (≥ 60 fps at 3840×2160) and progressive refinement to full quality (one frame on a GPU).
rb --frames 20 --warmup 3 --cycles 3 --size 3840x2160
if [ -x ./progressive_bench ]; then
  for size in 1280x720 1920x1080 3840x2160; do
    ./progressive_bench --volume 512 --size $size --budget 16 --views 4 --presets "$PWD/presets" >> "$OUT/progressive_bench.jsonl" 2>> "$OUT/progressive_bench.err"
  done
  cat "$OUT/progressive_bench.jsonl"
fi
tail -n 3 "$OUT/tests.log"
grep -v hover_cycle "$OUT/render_bench.jsonl"
true
