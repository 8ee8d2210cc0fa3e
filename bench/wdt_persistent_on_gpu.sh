#!/usr/bin/env bash
# On the lent GPU (device tool), one call: the persistent sweep (at::cuda::setPersistentSweeps: one
# cooperative launch a sweep, tiles synchronised with their 8 neighbours by progress counters)
# checked and timed against the group launches of the same build.
#   1. test_cuda's persistent cases (fixed passes = CPU bit for bit on one-wave, large-tile, edge
#      and thin grids; converged = exact reference bit for bit; repeated runs identical);
#   2. wdt_cuda_bench 256³ and 512³, both kernels alternating in one process, with the exact
#      reference and the CPU at 256³;
#   3. the whole test_cuda with the default (group launches);
#   4. the whole test_cuda again with AT_WDT_CUDA_PERSISTENT=1 (every older case on the new kernel);
#   5. wdt_cuda_bench again, kernels in the other order, no checks (the spread between rounds);
#   6. 512³ GPU = CPU bit for bit under the persistent kernel (large tile).
# Every stage runs under `timeout` within one overall budget (a wrong wait hangs rather than
# fails), a failing stage does not stop the next, and everything is packed into $OUT/wdt35.tgz
# after each stage, with $OUT/summary.txt beside it.
#   bash bench/wdt_persistent_on_gpu.sh DIR [BUDGET_S]   (DIR holding test_cuda and wdt_cuda_bench,
#                                                          as built by bench/pack_wdt_persistent.sh)
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
stage tests_persistent 40 "$N/test_cuda" -tc='persistent*'
stage bench1 50 "$N/wdt_cuda_bench" --sizes 256,512 --reps 10 --check-max 256 --sweep-kernel groups,persistent
stage tests_default 25 "$N/test_cuda" -tce='persistent*'
stage tests_all_persistent 25 env AT_WDT_CUDA_PERSISTENT=1 "$N/test_cuda" -tce='persistent*'
stage bench2 35 "$N/wdt_cuda_bench" --sizes 256,512 --reps 10 --check-max 0 --sweep-kernel persistent,groups
stage bench512cpu 40 "$N/wdt_cuda_bench" --sizes 512 --reps 1 --check-max 0 --cpu-check-max 512 --sweep-kernel persistent
set +x
python3 - "$R" <<'PY' | tee "$R/table.txt" || true
import json, sys, collections
r = sys.argv[1]
t = collections.defaultdict(list)
for name in ("bench1", "bench2", "bench512cpu"):
    try:
        lines = open(f"{r}/{name}.txt").read().splitlines()
    except OSError:
        continue
    for l in lines:
        if not l.startswith("{") or '"skipped"' in l:
            continue
        x = json.loads(l)
        key = (x["size"], x["mode"], x["sweep_kernel"])
        ms = x["ms_device_median"] if x["mode"] == "converge" else x["ms_per_pass_median"]
        t[key].append(f'{ms:.4f}' + ("" if name != "bench512cpu" else "(1 rep)"))
        flags = {k: x[k] for k in ("persistent_sweeps_captured", "gpu_equals_cpu_bitwise", "gpu_equals_exact_bitwise",
                                   "gpu_max_rel_err", "passes_run", "rounds", "scheme") if k in x}
        print(name, key, flags)
print("size, mode, kernel: ms per pass (converge: ms on the GPU), per round")
for k in sorted(t):
    print(k, t[k])
PY
pack
cat "$R/summary.txt"
true
