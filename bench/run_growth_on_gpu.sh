#!/usr/bin/env bash
# Grow from seeds on the GPU machine: the CUDA growth tests (GPU equals CPU and the exact
# reference bit for bit, incremental updates), the segment module's tests, and growth_bench on the
# GPU at 128³–512³ (8 labels) with the CPU engine beside it at 256³. Run from the repository root
# with .gpu/ carried, after `bash bench/collect_gpu_binaries.sh` here (no SDL2, DCMTK, SQLite or
# PostgreSQL in these binaries). Results go to $OUT:
#   machine.txt, growth_tests.log, growth_bench_cuda.jsonl, growth_bench_cpu.jsonl, growth_bench.err
set -uo pipefail
export LD_LIBRARY_PATH=$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
cd .gpu
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$OUT/machine.txt" 2>&1
log() { echo "== $*" >> "$OUT/growth_tests.log"; "$@" >> "$OUT/growth_tests.log" 2>&1; echo "   exit $?" >> "$OUT/growth_tests.log"; }
log ./test_cuda -tc='*Grow from seeds*,*Incremental GPU*'
[ -x ./test_segment ] && log ./test_segment
./growth_bench --sizes 128,256,512 --backends cuda --reps 5 --check-max 256 > "$OUT/growth_bench_cuda.jsonl" 2> "$OUT/growth_bench.err"
./growth_bench --sizes 256 --backends cpu --reps 1 --check-max 0 > "$OUT/growth_bench_cpu.jsonl" 2>> "$OUT/growth_bench.err"
grep -E "exit|test cases" "$OUT/growth_tests.log"
cat "$OUT/growth_bench_cuda.jsonl" "$OUT/growth_bench_cpu.jsonl"
true
