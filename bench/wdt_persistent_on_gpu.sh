#!/usr/bin/env bash
# On the lent GPU (device tool), one call: the persistent sweep (AT_WDT_CUDA_PERSISTENT=1, one
# launch a sweep, tiles synchronised with their 8 neighbours by progress counters) against the
# group launches of the same build. Exactness first (test_cuda's sweep cases under the persistent
# sweep, each run under a timeout: a wrong wait would hang, not fail), then wdt_cuda_bench at
# 256³ and 512³, alternating, two rounds (round 1 checks against the exact reference at 256³ and
# the CPU at 512³). Prediction (PTX, no device time): a group's instructions −28 % (1202 → ~870 a
# thread; the region walk and offsets move out of the group loop), no launch link a group (≈ 0.75
# µs) but one L2 round trip for the neighbours' counters: 512³ (issue-bound) 5.3 → ~4.2 ms a pass,
# 256³ (latency-bound) 1.04 → 0.9–1.1 ms.
#   bash bench/wdt_persistent_on_gpu.sh DIR   (DIR holding test_cuda and wdt_cuda_bench of this branch)
set -uo pipefail
N=${1:?build folder}
R=$OUT/p; mkdir -p "$R"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total,uuid --format=csv > "$R/machine.txt" 2>&1
t0=$(date +%s); stamp() { echo "$(($(date +%s) - t0)) s: $*" | tee -a "$R/summary.txt"; }
SW='*fixed-pass*,*thin volumes*,*converged GPU*,*two GPU runs*,*converge mode*'
AT_WDT_CUDA_PERSISTENT=1 timeout 90 "$N/test_cuda" -tc="$SW" > "$R/test_cuda_persistent.txt" 2>&1
stamp "test_cuda sweeps, persistent: exit $? (124: hung)"; tail -n 3 "$R/test_cuda_persistent.txt"
grep -B3 -A12 "ERROR" "$R/test_cuda_persistent.txt" | head -40
timeout 120 "$N/test_cuda" > "$R/test_cuda.txt" 2>&1; stamp "test_cuda (group launches) exit $?"; tail -n 3 "$R/test_cuda.txt"
bench() { local name=$1; shift; env "$@" | sed "s/^{/{\"build\":\"$name\",/" >> "$R/bench.jsonl"; stamp "bench $name"; }
for round in 1 2; do
  chk="--check-max 0"; [ $round = 1 ] && chk="--check-max 256 --cpu-check-max 512"
  bench groups timeout 60 "$N/wdt_cuda_bench" --sizes 256,512 --reps 10 --check-max 0
  bench persistent AT_WDT_CUDA_PERSISTENT=1 timeout 120 "$N/wdt_cuda_bench" --sizes 256,512 --reps 10 $chk
done
python3 - "$R" <<'PY'
import json, sys, collections
r = sys.argv[1]
rows = [json.loads(l) for l in open(r + "/bench.jsonl") if l.startswith("{")]
t = collections.defaultdict(list)
for x in rows:
    t[(x["size"], x["mode"], x["build"])].append(x["ms_per_pass_median"] if x["mode"] != "converge" else x["ms_device_median"])
for k in sorted(t): print(k, t[k])
for x in rows:
    if "gpu_equals_cpu_bitwise" in x or "gpu_max_rel_err" in x:
        print(x["build"], x["size"], x["mode"], "gpu=cpu", x.get("gpu_equals_cpu_bitwise"), "maxrel", x.get("gpu_max_rel_err"))
PY
true
