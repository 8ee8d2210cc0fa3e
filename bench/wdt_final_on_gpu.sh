#!/usr/bin/env bash
# On the lent GPU (device tool), one call, a new build against a baseline build: test_cuda of the
# new build (also with the growth's ordered rounds forced to tiny windows), growth_bench at 256³
# and 512³ (8 labels) with the ordered rounds' settings (AT_CUDA_GROWTH_ORDER: default, 2,8, 8,32,
# and 0 = unordered) and the baseline, and wdt_cuda_bench at 128³–512³ of both builds alternately,
# two rounds (the new build's fields checked against the CPU at 512³ and the exact reference at
# 256³ in round 1; AT_WDT_CUDA_LARGE_TILE=0 beside it at 512³); with WITH_LARGE=1 also 768³ and
# 1024³ of both builds (the new one checked against the CPU at 1024³) and 1536³ of the new build.
# Results in $OUT/f; a summary last.
#   bash bench/wdt_final_on_gpu.sh NEW_DIR BASE_DIR   (each with test_cuda, wdt_cuda_bench, growth_bench)
set -uo pipefail
N=${1:?new build folder}; B=${2:?baseline build folder}
R=$OUT/f; mkdir -p "$R"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total,uuid --format=csv > "$R/machine.txt" 2>&1
t0=$(date +%s); stamp() { echo "$(($(date +%s) - t0)) s: $*" | tee -a "$R/summary.txt"; }
timeout 150 "$N/test_cuda" > "$R/test_cuda.txt" 2>&1; stamp "test_cuda exit $?"
tail -n 3 "$R/test_cuda.txt"; grep -B3 -A12 "ERROR" "$R/test_cuda.txt" | head -40
AT_CUDA_GROWTH_ORDER=1,2 timeout 90 "$N/test_cuda" -tc='*Grow*,*Incremental*' > "$R/test_cuda_order12.txt" 2>&1
stamp "test_cuda growth (order 1,2) exit $?"; tail -n 2 "$R/test_cuda_order12.txt"
grow() {  # label env... binary args
  local name=$1; shift
  env "$@" | sed "s/^{/{\"build\":\"$name\",/" >> "$R/growth.jsonl"; stamp "growth $name"
}
grow base timeout 90 "$B/growth_bench" --sizes 256,512 --backends cuda --reps 3 --check-max 0
grow new timeout 150 "$N/growth_bench" --sizes 256,512 --backends cuda --reps 3 --check-max 256
grow new-2,8 AT_CUDA_GROWTH_ORDER=2,8 timeout 90 "$N/growth_bench" --sizes 256,512 --backends cuda --reps 3 --check-max 0
grow new-8,32 AT_CUDA_GROWTH_ORDER=8,32 timeout 90 "$N/growth_bench" --sizes 256,512 --backends cuda --reps 3 --check-max 0
grow new-unordered AT_CUDA_GROWTH_ORDER=0 timeout 90 "$N/growth_bench" --sizes 256,512 --backends cuda --reps 3 --check-max 0
grow base2 timeout 90 "$B/growth_bench" --sizes 512 --backends cuda --reps 3 --check-max 0
grow new2 timeout 90 "$N/growth_bench" --sizes 512 --backends cuda --reps 3 --check-max 0
bench() {  # label env... binary args
  local name=$1; shift
  env "$@" | sed "s/^{/{\"build\":\"$name\",/" >> "$R/bench.jsonl"; stamp "sweeps $name"
}
for round in 1 2; do
  chk="--check-max 0"; [ $round = 1 ] && chk="--check-max 256 --cpu-check-max 512"
  bench base timeout 60 "$B/wdt_cuda_bench" --sizes 128,256,512 --reps 10 --check-max 0
  bench new timeout 150 "$N/wdt_cuda_bench" --sizes 128,256,512 --reps 10 $chk
  bench new-nolarge AT_WDT_CUDA_LARGE_TILE=0 timeout 60 "$N/wdt_cuda_bench" --sizes 512 --reps 10 --check-max 0
done
if [ "${WITH_LARGE:-0}" = 1 ]; then  # 768³–1536³: several waves of the large tile
  bench base timeout 150 "$B/wdt_cuda_bench" --sizes 768,1024 --reps 3 --check-max 0
  bench new timeout 200 "$N/wdt_cuda_bench" --sizes 768,1024 --reps 3 --check-max 0 --cpu-check-max 1024
  bench new timeout 120 "$N/wdt_cuda_bench" --sizes 1536 --reps 1 --check-max 0
fi
python3 - "$R" <<'PY'
import json, sys, collections
r = sys.argv[1]
def rows(f):
    try: return [json.loads(l) for l in open(r + f) if l.startswith("{")]
    except FileNotFoundError: return []
t = collections.defaultdict(list)
for x in rows("/bench.jsonl"):
    t[(x["size"], x["mode"], x["build"])].append(x["ms_per_pass_median"] if x["mode"] != "converge" else x["ms_device_median"])
for k in sorted(t): print(k, t[k])
for x in rows("/bench.jsonl"):
    if "max_rel_diff_gpu_cpu" in x: print(x["build"], x["size"], x["mode"], "gpu-cpu", x["max_rel_diff_gpu_cpu"], x.get("gpu_equals_cpu_bitwise"), "maxrel", x.get("gpu_max_rel_err"), "rounds", x.get("rounds"), "MiB", x.get("device_mib_used"))
for x in rows("/growth.jsonl"):
    print("growth", x["build"], x["size"], x["step"], "compute", x["ms_compute"], "wall", x["ms_wall"], "visits", x["brick_visits"], "rounds", x["rounds"], "exact", x["exact_equal"])
PY
tar czf "$OUT/final.tgz" -C "$OUT" f
true
