#!/usr/bin/env bash
# On the lent GPU (device tool), one call: the default that runs the large tile's sweeps as
# persistent launches (at::cuda::setPersistentSweeps Auto), checked and timed against the group
# launches and the persistent sweep for every tile:
#   1. test_cuda's persistent cases; 2.–4. the whole test_cuda with the default,
#   AT_WDT_CUDA_PERSISTENT=1 and =0; 5. wdt_cuda_bench 256³/512³, kernels auto, groups and
#   persistent in one process, exact reference and CPU at 256³; 6. again in the other order with
#   128³; 7. 512³ GPU = CPU under the default; 8. 1024³ under the default (device memory stated).
#   bash bench/wdt_persistent_default_on_gpu.sh DIR [BUDGET_S]  (DIR as built by bench/pack_wdt_persistent.sh)
set -uo pipefail
set -x
N=${1:?folder with test_cuda and wdt_cuda_bench}
BUDGET=${2:-120}
R=/tmp/wdt35; rm -rf "$R"; mkdir -p "$R"
T0=$(date +%s)
left() { echo $((BUDGET - ($(date +%s) - T0))); }
stamp() { echo "$(($(date +%s) - T0)) s: $*" | tee -a "$R/summary.txt"; }
pack() { tar -czf "$OUT/wdt35.tgz" -C /tmp wdt35 || true; cp "$R/summary.txt" "$OUT/summary.txt" || true; }
# stage NAME CAP_S COMMAND…: runs COMMAND (stdout+stderr to NAME.txt) for at most CAP_S seconds and
# at most what is left of the budget.
stage() {
  local name=$1 limit=$2 l rc
  shift 2
  l=$(left)
  [ "$l" -lt "$limit" ] && limit=$l
  if [ "$limit" -lt 3 ]; then stamp "$name skipped (budget spent)"; return; fi
  timeout -k 3 "$limit" "$@" > "$R/$name.txt" 2>&1
  rc=$?
  stamp "$name exit $rc (limit $limit s; 124: timed out, hung or slow)"
  tail -n 4 "$R/$name.txt" || true
  grep -m 12 -B2 -A8 "ERROR" "$R/$name.txt" || true
  pack
}
{ nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total,uuid --format=csv; nvidia-smi -L; } > "$R/machine.txt" 2>&1 || true
cat "$R/machine.txt"
B="$N/wdt_cuda_bench"
stage tests_persistent 40 "$N/test_cuda" -tc='persistent*'
stage tests_default 30 "$N/test_cuda"
stage tests_all_persistent 30 env AT_WDT_CUDA_PERSISTENT=1 "$N/test_cuda" -tce='persistent*'
stage tests_groups 30 env AT_WDT_CUDA_PERSISTENT=0 "$N/test_cuda" -tce='persistent*'
stage bench1 80 "$B" --sizes 256,512 --reps 10 --check-max 256 --sweep-kernel auto,groups,persistent
stage bench2 70 "$B" --sizes 128,256,512 --reps 10 --check-max 0 --sweep-kernel persistent,groups,auto
stage bench512cpu 40 "$B" --sizes 512 --reps 1 --check-max 0 --cpu-check-max 512
stage bench1024 90 "$B" --sizes 1024 --reps 3 --check-max 0
set +x
python3 - "$R" <<'PY' | tee "$R/table.txt" || true
import json, sys, collections
r = sys.argv[1]
t = collections.defaultdict(list)
for name in ("bench1", "bench2", "bench512cpu", "bench1024"):
    try:
        lines = open(f"{r}/{name}.txt").read().splitlines()
    except OSError:
        continue
    for l in lines:
        if not l.startswith("{") or '"skipped"' in l:
            continue
        x = json.loads(l)
        kernel = x["sweep_kernel"]
        key = (x["size"], x["mode"], kernel)
        ms = x["ms_device_median"] if x["mode"] == "converge" else x["ms_per_pass_median"]
        t[key].append(f'{ms:.4f}' + ("" if name not in ("bench512cpu", "bench1024") else f'({x["runs"]} rep)'))
        flags = {k: x[k] for k in ("persistent_sweeps_captured", "gpu_equals_cpu_bitwise", "gpu_equals_exact_bitwise",
                                   "gpu_max_rel_err", "passes_run", "rounds", "device_mib_used") if k in x}
        print(name, key, flags)
print("size, mode, kernel: ms per pass (converge: ms on the GPU), per round")
for k in sorted(t):
    print(k, t[k])
PY
grep -hE "test cases|assertions" "$R"/tests_*.txt | tee -a "$R/summary.txt"
pack
cat "$R/summary.txt"
true
