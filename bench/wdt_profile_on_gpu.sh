#!/usr/bin/env bash
# Profiles the CUDA WDT pass on the lent GPU (device tool): machine, test_cuda, per-pass timings
# of wdt_cuda_bench, and Nsight Compute metrics of every kernel of one pass at 256³ and 512³
# (sweep groups and transposes, serialised by ncu), plus the SASS of the sweep kernels.
#   bash bench/wdt_profile_on_gpu.sh DIR     DIR holds test_cuda and wdt_cuda_bench; results in $OUT
set -uo pipefail
B=${1:?binary folder}
R=$OUT/r; mkdir -p "$R"
{ nvidia-smi -L; nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.sm,clocks.mem,memory.total --format=csv; nproc; free -g; } > "$R/machine.txt" 2>&1
"$B/test_cuda" > "$R/test_cuda.log" 2>&1; echo "test_cuda exit $?" | tee -a "$R/summary.txt"
tail -n 3 "$R/test_cuda.log"
"$B/wdt_cuda_bench" --sizes 128,256,512 --reps 10 --check-max 0 > "$R/bench.jsonl" 2>&1
cat "$R/bench.jsonl"
M=gpu__time_duration.sum,launch__grid_size,launch__block_size,launch__registers_per_thread,launch__waves_per_multiprocessor,launch__occupancy_limit_registers,sm__maximum_warps_per_active_cycle_pct,sm__warps_active.avg.pct_of_peak_sustained_active,sm__throughput.avg.pct_of_peak_sustained_elapsed,dram__throughput.avg.pct_of_peak_sustained_elapsed,lts__throughput.avg.pct_of_peak_sustained_elapsed,smsp__issue_active.avg.pct_of_peak_sustained_active,smsp__inst_executed.sum,dram__bytes_read.sum,dram__bytes_write.sum
for n in 256 512; do
  # Launch 0 of the filter is the density transpose of the set-up; the next 2 + 6·ceil(n/8) are
  # the warm-up run's one pass.
  cnt=$((2 + 6 * ((n + 7) / 8)))
  timeout 200 ncu --clock-control none --csv --metrics $M -k regex:'sweepGroup|transposeXY' --launch-skip 1 \
    --launch-count $cnt "$B/wdt_cuda_bench" --sizes $n --reps 1 --check-max 0 > "$R/ncu_$n.csv" 2> "$R/ncu_$n.err"
  echo "ncu $n exit $?" | tee -a "$R/summary.txt"
done
timeout 120 ncu --clock-control none --section SpeedOfLight --section Occupancy --section LaunchStats --section WarpStateStats \
  --section SchedulerStats -k regex:sweepGroup --launch-skip 40 --launch-count 1 "$B/wdt_cuda_bench" --sizes 256 --reps 1 --check-max 0 > "$R/ncu_sections_256.txt" 2>&1
cuobjdump --dump-sass "$B/wdt_cuda_bench" 2>/dev/null | gzip > "$R/sass.txt.gz"
"$B/wdt_cuda_bench" --sizes 1024 --reps 2 --check-max 0 > "$R/bench_1024.jsonl" 2>&1; cat "$R/bench_1024.jsonl"
nvidia-smi --query-gpu=memory.used,memory.total --format=csv >> "$R/machine.txt"
tar czf "$OUT/profile.tgz" -C "$OUT" r && rm -rf "$R"
