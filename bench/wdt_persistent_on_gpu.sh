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
#   6. 512³ GPU = CPU bit for bit under the persistent kernel (large tile);
#   7. (if growth_bench is in DIR) label growth at 512³ with 8 labels, CUDA, and at 1024³ with the
#      GPU's used memory sampled by nvidia-smi every 100 ms (peak in growth1024_mem.txt);
#   8. (if ncu is on the PATH) an Nsight Compute profile of the persistent sweep at 256³ (its first
#      6 launches: one pass) and of the group launches' kernel (12 launches), clocks left alone.
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
if [ -x "$N/growth_bench" ]; then
  stage growth512 60 "$N/growth_bench" --sizes 512 --backends cuda --reps 3 --check-max 0
  nvidia-smi --query-gpu=timestamp,memory.used --format=csv -lms 100 > "$R/growth1024_mem.txt" 2>&1 &
  SMI=$!
  stage growth1024 90 "$N/growth_bench" --sizes 1024 --backends cuda --reps 1 --check-max 0
  kill "$SMI" 2>/dev/null
  python3 -c "import sys; v=[int(l.split(',')[1].split()[0]) for l in open(sys.argv[1]) if 'MiB' in l and l[0].isdigit()]; print('growth 1024 peak GPU memory used:', max(v) if v else '?', 'MiB; before:', v[0] if v else '?')" "$R/growth1024_mem.txt" | tee -a "$R/summary.txt"
fi
if command -v ncu >/dev/null; then
  NCU="ncu --clock-control none --section SpeedOfLight --section LaunchStats --section Occupancy --section WarpStateStats --section SchedulerStats --section MemoryWorkloadAnalysis"
  stage ncu_persistent256 90 env AT_WDT_CUDA_PERSISTENT=1 $NCU -k regex:sweepPersistent --launch-count 6 "$N/wdt_cuda_bench" --sizes 256 --reps 1 --check-max 0 --sweep-kernel persistent
  stage ncu_groups256 60 $NCU -k regex:sweepGroup --launch-count 12 "$N/wdt_cuda_bench" --sizes 256 --reps 1 --check-max 0 --sweep-kernel groups
fi
set +x
python3 - "$R" <<'PY' | tee "$R/table.txt" || true
import json, sys, collections
r = sys.argv[1]
t = collections.defaultdict(list)
for name in ("bench1", "bench2", "bench512cpu", "bench3"):
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
