#!/usr/bin/env bash
# Grow from seeds on the lent GPU (device tool), builds side by side: test_cuda of each new build
# (its growth cases: GPU = CPU = exact reference), growth_bench at 256³ and 512³ (8 labels) of the
# baseline and the new builds alternately, two rounds, and ncu occupancy of the solve kernel at
# 512³. Results in $OUT/g/; a summary is printed last.
#   bash bench/growth_compare_on_gpu.sh BASE_DIR NEW_DIR...   (each with growth_bench; new ones also test_cuda)
set -uo pipefail
BASE=${1:?baseline build folder}; shift
R=$OUT/g; mkdir -p "$R"
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,memory.total --format=csv > "$R/machine.txt" 2>&1
for d in "$@"; do
  n=$(basename "$d")
  timeout 200 "$d/test_cuda" > "$R/test_cuda_$n.log" 2>&1
  echo "test_cuda $n exit $? $(grep -E '^\[doctest\] (test cases|assertions)' "$R/test_cuda_$n.log" | tr '\n' ' ')" | tee -a "$R/summary.txt"
  grep -B3 -A12 "ERROR" "$R/test_cuda_$n.log" | head -30
done
for round in 1 2; do
  for d in "$BASE" "$@"; do
    n=$(basename "$d"); chk=0; [ $round = 1 ] && chk=256
    timeout 120 "$d/growth_bench" --sizes 256,512 --backends cuda --reps 5 --check-max $chk 2>> "$R/growth.err" \
      | sed "s/^{/{\"build\":\"$n\",\"round\":$round,/" >> "$R/growth.jsonl"
  done
done
M=gpu__time_duration.sum,sm__warps_active.avg.pct_of_peak_sustained_active,launch__occupancy_limit_registers,launch__occupancy_limit_shared_mem,launch__registers_per_thread,launch__grid_size
for d in "$BASE" "$@"; do
  n=$(basename "$d")
  timeout 90 ncu --clock-control none --csv --metrics $M -k regex:solveGrowth --launch-count 1 \
    "$d/growth_bench" --sizes 512 --backends cuda --reps 1 --check-max 0 > "$R/ncu_$n.csv" 2>&1
done
python3 - "$R" <<'PY'
import collections, csv, glob, json, sys
r = sys.argv[1]
t = collections.defaultdict(list)
for l in open(r + "/growth.jsonl"):
    if not l.startswith("{"): continue
    x = json.loads(l)
    t[(x["size"], x["step"], x["build"])].append((x["ms_wall"], x["ms_compute"], x.get("brick_visits"), x.get("rounds"), x.get("exact_equal")))
for k in sorted(t): print(k, t[k])
for f in sorted(glob.glob(r + "/ncu_*.csv")):
    vals = {}
    for row in csv.reader(l for l in open(f) if l.startswith('"')):
        if len(row) > 14 and row[0] != "ID": vals[row[-3]] = row[-1]
    print(f.split("/")[-1], vals)
PY
cat "$R/summary.txt"
