#!/usr/bin/env bash
# The WDT's GPU checks and timings for one build against another on the lent GPU (device tool):
# test_cuda of the new build, wdt_cuda_bench of both builds alternately at 128³–512³ (the same
# machine, so the difference is the code's), the new build at 1024³ (GPU = CPU bit for bit) and
# 1536³ with the device memory used, ncu metrics of one 256³ sweep launch of each, and the
# grow-from-seeds benchmark at 512³. Results in $OUT/wdt.tgz; a summary is printed last.
#   bash bench/wdt_bandwidth_on_gpu.sh NEW_DIR BASE_DIR   (each with test_cuda, wdt_cuda_bench, growth_bench)
set -uo pipefail
N=${1:?new build folder}; B=${2:?baseline build folder}
R=$OUT/w; mkdir -p "$R"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total --format=csv > "$R/machine.txt" 2>&1
"$N/test_cuda" > "$R/test_cuda.log" 2>&1; echo "test_cuda exit $?" | tee -a "$R/summary.txt"
tail -n 3 "$R/test_cuda.log"; grep -B3 -A12 "ERROR" "$R/test_cuda.log" | head -60
for round in 1 2; do
  for v in new base; do
    d=$N; [ $v = base ] && d=$B
    chk=0; [ $round = 1 ] && [ $v = new ] && chk=256
    "$d/wdt_cuda_bench" --sizes 128,256,512 --reps 10 --check-max $chk | sed "s/^{/{\"build\":\"$v\",\"round\":$round,/" >> "$R/bench.jsonl"
  done
done
M=gpu__time_duration.sum,smsp__inst_executed.sum,smsp__issue_active.avg.pct_of_peak_sustained_active,sm__warps_active.avg.pct_of_peak_sustained_active,launch__registers_per_thread
for v in new base; do
  d=$N; [ $v = base ] && d=$B
  timeout 60 ncu --clock-control none --csv --metrics $M -k regex:sweepGroup --launch-skip 40 --launch-count 4 \
    "$d/wdt_cuda_bench" --sizes 256 --reps 1 --check-max 0 > "$R/ncu_$v.csv" 2>&1
done
timeout 150 "$N/wdt_cuda_bench" --sizes 1024 --reps 2 --check-max 0 --cpu-check-max 1024 >> "$R/bench_big.jsonl" 2>> "$R/bench_big.err"
echo "1024 exit $?" | tee -a "$R/summary.txt"
timeout 100 "$N/growth_bench" --sizes 512 --backends cuda --reps 3 --check-max 0 > "$R/growth.jsonl" 2>&1
timeout 170 "$N/wdt_cuda_bench" --sizes 1536 --reps 1 --check-max 0 >> "$R/bench_big.jsonl" 2>> "$R/bench_big.err"
echo "1536 exit $?" | tee -a "$R/summary.txt"
tar czf "$OUT/wdt.tgz" -C "$OUT" w
python3 - "$R" <<'PY'
import json, sys, collections
r = sys.argv[1]
rows = [json.loads(l) for l in open(r + "/bench.jsonl") if l.startswith("{")]
t = collections.defaultdict(list)
for x in rows:
    t[(x["size"], x["mode"], x["build"])].append(x["ms_per_pass_median"] if x["mode"] != "converge" else x["ms_device_median"])
for k in sorted(t): print(k, t[k])
for x in rows:
    if "gpu_max_rel_err" in x: print(x["size"], x["mode"], "maxrel", x["gpu_max_rel_err"], "below", x["gpu_below_exact"], "gpu-cpu", x["max_rel_diff_gpu_cpu"])
for l in open(r + "/bench_big.jsonl"): print(l.strip()[:400])
print(open(r + "/growth.jsonl").read()[-1500:])
PY
